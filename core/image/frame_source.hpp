// Frames of light over time: one image, a numbered image sequence
// (frame_0001.exr, frame_0002.exr, ...) or a video file, behind one interface
// so the light-rig tool never cares which it was given.
//
// Sequences: the frame number is the last run of digits in the file name;
// its width is the padding. Given one frame, the sequence is every file in
// that folder with the same prefix, padding and suffix. A gap in the numbers
// is an error naming the missing files (a render that died half-way should
// not become a light rig that silently skips time). Every frame must have the
// first frame's size.
//
// Videos are decoded by FFmpeg in a child process (image/video.hpp).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "image/image.hpp"

namespace penumbra {

class FrameSource {
public:
    virtual ~FrameSource() = default;
    virtual int frame_count() const = 0;
    virtual int width() const = 0;
    virtual int height() const = 0;
    virtual double frames_per_second() const = 0;  // 0 when unknown (images)
    // Frame `index` in [0, frame_count()) as float RGB, as stored in the file.
    virtual Image read(int index) const = 0;
    virtual std::string describe() const = 0;
};

enum class FrameSourceKind { automatic, single_image, sequence, video };

// Opens `path` as the given kind; `automatic` picks video for a movie file (by extension), a sequence when the name has a
// frame number and neighbours exist, else a single image. Throws IoError.
std::unique_ptr<FrameSource> open_frames(const std::string& path,
                                         FrameSourceKind kind = FrameSourceKind::automatic);

// The files of the sequence `first_frame` belongs to, in frame order, and
// their frame numbers. Throws IoError on gaps or when nothing matches.
struct SequenceFiles {
    std::vector<std::string> paths;
    std::vector<int> numbers;
};
SequenceFiles find_sequence(const std::string& first_frame);

}  // namespace penumbra
