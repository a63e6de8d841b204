// Fuzz harness: a video file opened end to end as the light-rig tool opens
// it, open_frames(kind video) in core/image/frame_source.cpp, decoded by the
// ffmpeg the package ships ($PENUMBRA_FFMPEG) in a child process. Slow (each
// input starts ffmpeg two or three times), so it runs few inputs; the
// video_decoder harness fuzzes our parsing of ffmpeg's output fast.
//
// Input: the file's bytes, named by what their first bytes announce (.mp4 for
// an ISO-BMFF 'ftyp', .mkv for EBML, .avi for RIFF, else .mov).
// Checked: only penumbra::Error; frames read have the probed size.
#include <cstring>

#include "../fuzz_util.hpp"
#include "image/frame_source.hpp"

using namespace penumbra;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const char* ext = ".mov";
    if (size >= 8 && std::memcmp(data + 4, "ftyp", 4) == 0) ext = ".mp4";
    else if (size >= 4 && std::memcmp(data, "\x1a\x45\xdf\xa3", 4) == 0) ext = ".mkv";
    else if (size >= 4 && std::memcmp(data, "RIFF", 4) == 0) ext = ".avi";
    fuzz::Scratch::get().fresh();
    const std::string path = fuzz::Scratch::get().file(std::string("input") + ext);
    fuzz::write_file(path, data, size);
    fuzz::expect_only_penumbra_errors([&] {
        const auto source = open_frames(path, FrameSourceKind::video);
        const int n = source->frame_count();
        penumbra_fuzz_check(n >= 1 && source->width() > 0 && source->height() > 0, "a video without frames was accepted");
        for (int index : {0, n - 1}) {
            const Image image = source->read(index);
            penumbra_fuzz_check(image.width == source->width() && image.height == source->height(),
                                "a decoded frame does not have the probed size");
        }
    });
    return 0;
}
