// Planar Y′CbCr video frames, as FFmpeg's decoders hand them out, to RGB the
// way FFmpeg's own scaler (libswscale with its default flags) converts them,
// so video.cpp can take a decoder's native frames through the pipe (1.5 to 3
// bytes per pixel) instead of float RGB (12) and convert on its own threads.
//
// What FFmpeg does and this follows (measured against its gbrpf32le output,
// tests/cpp/image/video_test.cpp):
//   matrix   the stream's colour space: BT.709; BT.601 for bt470bg,
//            smpte170m and an unspecified one (swscale's default); BT.2020
//            non-constant luminance; SMPTE 240M; FCC;
//   range    limited ("tv": Y′ 16..235, C 16..240, scaled by 2^(bits − 8))
//            unless the stream says full ("pc") or the format is a JPEG one
//            (yuvj*);
//   chroma   4:2:0 and 4:2:2 chroma upsampled with swscale's default bicubic
//            (Keys a = −0.6), sample positions centred between luma samples,
//            edges repeated;
//   output   R′G′B′ clipped to [0, 1], as swscale's float output is.
// Anything else (RGB, grey, semi-planar, big-endian, constant-luminance or
// YCgCo matrices) is left to FFmpeg: yuv_format() says no.
#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include "image/image.hpp"

namespace penumbra {

struct YuvFormat {
    std::string pixel_format;  // FFmpeg's name, asked of the decoder as is
    int width = 0, height = 0;
    int chroma_shift_x = 0, chroma_shift_y = 0;  // log2 of the subsampling
    int bits = 8;                // per sample: 8 (one byte) or 9..16 (two, little-endian)
    bool alpha = false;          // a fourth plane follows (ignored)
    bool full_range = false;
    double kr = 0.299, kb = 0.114;  // luma coefficients of the matrix
    int chroma_width() const { return -((-width) >> chroma_shift_x); }
    int chroma_height() const { return -((-height) >> chroma_shift_y); }
    std::size_t frame_bytes() const;  // one rawvideo frame
};

// The native layout of a stream FFmpeg describes as `pixel_format` (e.g.
// "yuv420p10le") with `color_range` ("tv", "pc" or "") and `color_space`
// (FFmpeg's name, "" when unspecified), when this file converts it.
std::optional<YuvFormat> yuv_format(const std::string& pixel_format, const std::string& color_range,
                                    const std::string& color_space, int width, int height);

// One rawvideo frame of `format` to float RGB in `out` (resized to
// width × height × 3), rows in parallel on up to `threads` (0: all cores).
void yuv_to_rgb(const YuvFormat& format, const unsigned char* frame, Image& out, int threads = 0);

}  // namespace penumbra
