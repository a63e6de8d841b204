// Reading frames of lighting from files with bounded memory.
//
// A 16384×8192 EXR is 1.6 GB as float RGB (2.1 GB more while OpenImageIO
// hands over RGBA), yet the light rig works on at most `max_width` columns
// (2048 by default). read_environment reads a file wider than max_width
// band by band with OpenImageIO's read_scanlines, top to bottom, so memory
// stays at a few bands plus the working map. Per band: pick R, G, B (as
// core/image's read_image does), convert to scene-linear, zero and count
// bad values, add the band's Σ Y·Ω, then
//   lat-long      reduce the band (energy-exact, the same code as
//                 make_environment): bit-identical to read_image +
//                 ColorConfig::to_scene_linear + make_environment (tested);
//   fisheye,      take the look-ups whose top row is in the band
//   mirror ball   (BandResampler, environment.hpp): the same look-ups as the
//                 whole image's, equal to it within one float ulp (tested).
// Images no wider than max_width are read whole. LightSource adds the file
// names behind a FrameSource, so single images and sequence frames stream
// in every projection; video frames come whole from ffmpeg's pipe.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "color/color_config.hpp"
#include "common/progress.hpp"
#include "image/frame_source.hpp"
#include "lights/environment.hpp"

namespace penumbra::lights {

struct ReadReport {
    bool streamed = false;          // read band by band (else whole)
    int bands = 0;                  // bands read
    // Largest buffers held at once (bytes), excluding the working map: input
    // rows, and for fisheye / mirror ball the band index and partial sums.
    std::size_t buffer_bytes = 0;
};

// One image file (subimage 0) as a working map. `config` null: no colour
// conversion. `band_bytes` bounds the rows of input held at once (at least
// the rows one output row needs, or one row and the next for fisheye and
// mirror ball). Throws IoError for unreadable files, ArgumentError for bad
// options, Error for an unknown colour space.
EnvironmentMap read_environment(const std::string& path, const ColorConfig* config, const std::string& colorspace,
                                const MapOptions& options, const Progress& progress = {},
                                std::size_t band_bytes = std::size_t(16) << 20, ReadReport* report = nullptr);

// Whether read_environment streams a width×height input under `options`.
bool streams(const MapOptions& options, int width, int height);

class LightSource {
public:
    // `band_bytes`: read_environment's bound on the input rows held at once.
    explicit LightSource(const std::string& path, FrameSourceKind kind = FrameSourceKind::automatic,
                         std::size_t band_bytes = std::size_t(16) << 20);
    const FrameSource& frames() const { return *frames_; }
    // The file of each frame (empty for a video).
    const std::vector<std::string>& files() const { return files_; }
    // Frame `index` as a working map, converted from `colorspace` (config
    // null: none). Image files stream (read_environment), whatever the
    // projection; video frames are read whole. Every frame must have the
    // first frame's size (IoError).
    EnvironmentMap read_map(int index, const ColorConfig* config, const std::string& colorspace,
                            const MapOptions& options, const Progress& progress = {},
                            ReadReport* report = nullptr) const;

private:
    std::unique_ptr<FrameSource> frames_;
    std::vector<std::string> files_;
    std::size_t band_bytes_;
};

}  // namespace penumbra::lights
