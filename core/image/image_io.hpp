// Reading and writing single images through OpenImageIO.
//
// Reads any format OpenImageIO knows (EXR, Radiance HDR, PNG, TIFF, ...) into
// float RGB, whatever the file holds:
//   1 channel  -> grey copied to R, G and B
//   2 channels -> grey + alpha: grey copied to R, G, B, alpha dropped
//   3 channels -> as stored
//   4+ channels -> the channels named R, G, B (else the first three); alpha
//                  and the rest dropped, values kept as stored (EXR RGB is
//                  premultiplied; a light or a colour map wants exactly that)
// Pixel values are returned unchanged: NaN and Inf stay in (see
// image/image.hpp `sanitize`), colour space conversion is color/'s job.
//
// Writes are atomic: the image goes to a temporary name in the target folder
// (same extension, so the format is the same) and is renamed over the target
// only once complete, so a failure never leaves a half-written file.
#pragma once

#include <string>

#include "image/image.hpp"

namespace penumbra {

struct ImageInfo {
    int width = 0;
    int height = 0;
    int file_channels = 0;     // channels in the file, before conversion to RGB
    int subimages = 1;         // parts of a multi-part file
    std::string format;        // OpenImageIO's format name: "openexr", "png", ...
    std::string colorspace;    // colour space recorded in the file, "" if none
};

// Header only; throws IoError for a missing, empty, truncated or unknown file.
ImageInfo read_image_info(const std::string& path);

// Subimage `subimage` (a part of a multi-part file) as float RGB. Throws IoError.
// Videos are read through image/video.hpp.
Image read_image(const std::string& path, int subimage = 0);

enum class ExrPrecision { half, full };

// Float RGB(A) to OpenEXR (ZIP compression), `colorspace` recorded in the
// header. Throws ArgumentError for an empty image, IoError on failure.
void write_exr(const std::string& path, const Image& image,
               ExrPrecision precision, const std::string& colorspace);

// 16-bit PNG; values are written as they are, clamped to [0, 1] (convert to a
// display space first with color/), `colorspace` recorded in the file.
void write_png16(const std::string& path, const Image& image, const std::string& colorspace);

}  // namespace penumbra
