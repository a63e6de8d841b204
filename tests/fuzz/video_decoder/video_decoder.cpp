// Fuzz harness: our side of video decoding, core/image/video.cpp,
// core/image/yuv.cpp and core/common/child_process.cpp, with the fuzzer
// playing ffmpeg. probe_video parses ffmpeg's framecrc listing (dimensions,
// time base, one line per packet) and its description of the stream on
// stderr (pixel format, range, colour space); VideoReader reads raw frames
// (planar float RGB, or the decoder's planar YUV, converted here) from the
// child's stdout and restarts it to go back. Running the real ffmpeg on each input is the
// video_file harness; here a two-line shell script stands in for it, so an
// input costs two small process starts instead of two decodes, and the
// listing and frame bytes can be anything, not only what ffmpeg writes.
//
// Input: byte 0 sets the exit status of the stand-in: low nibble 0xF makes
// the probe fail, high nibble 0xF the decode. Then the listing, up to the
// first NUL byte (printed on the probe's stdout and stderr alike);
// everything after it is the decoder's stdout.
// Checked: only penumbra::Error; an accepted video has a positive size and
// frame count, and every frame read has that size.
#include <sys/stat.h>

#include "../fuzz_util.hpp"
#include "image/frame_source.hpp"
#include "image/video.hpp"

using namespace penumbra;

namespace {

const char* const stand_in = R"(#!/bin/sh
d=$(dirname "$0")
case " $* " in *" framecrc "*) cat "$d/listing"; cat "$d/listing" >&2; exit $(cat "$d/probe_status");; esac
cat "$d/frames"; exit $(cat "$d/decode_status")
)";

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fuzz::Bytes in(data, size);
    const std::uint8_t status = in.byte();
    std::string listing, frames = in.rest();
    const std::size_t nul = frames.find('\0');
    listing = frames.substr(0, nul);
    frames = nul == std::string::npos ? std::string() : frames.substr(nul + 1);

    auto& scratch = fuzz::Scratch::get();
    scratch.fresh();
    const std::string program = scratch.file("ffmpeg");
    fuzz::write_file(program, stand_in, std::strlen(stand_in));
    ::chmod(program.c_str(), 0755);
    fuzz::write_file(scratch.file("listing"), listing.data(), listing.size());
    fuzz::write_file(scratch.file("frames"), frames.data(), frames.size());
    const std::string probe_status = (status & 0x0f) == 0x0f ? "1" : "0";
    const std::string decode_status = (status & 0xf0) == 0xf0 ? "1" : "0";
    fuzz::write_file(scratch.file("probe_status"), probe_status.data(), 1);
    fuzz::write_file(scratch.file("decode_status"), decode_status.data(), 1);
    const std::string video = scratch.file("input.mp4");
    fuzz::write_file(video, "video", 5);
    set_ffmpeg_executable(program);

    fuzz::expect_only_penumbra_errors([&] {
        VideoReader reader(video);
        const VideoInfo& info = reader.info();
        penumbra_fuzz_check(info.width > 0 && info.height > 0 && info.frame_count > 0,
                            "probe_video accepted a video without frames");
        for (int index : {-1, info.frame_count}) {
            try {
                reader.read(index);
                penumbra::fuzz::finding("VideoReader::read accepted a frame index out of range");
            } catch (const ArgumentError&) {
            }
        }
        // In order, then back to the start (a restart of the decoder).
        for (int index : {0, info.frame_count - 1, 0}) {
            const Image image = reader.read(index);
            penumbra_fuzz_check(image.width == info.width && image.height == info.height && image.channels == 3 &&
                                    image.pixels.size() == image.pixel_count() * 3,
                                "a decoded frame does not have the probed size");
        }
    });
    return 0;
}
