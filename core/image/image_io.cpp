#include "image/image_io.hpp"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <memory>

#include "common/durable_file.hpp"
#include "common/error.hpp"

namespace penumbra {

namespace fs = std::filesystem;

namespace {

std::string last_oiio_error(const std::string& fallback) {
    std::string e = OIIO::geterror();
    return e.empty() ? fallback : e;
}

// Opens `path`, turning every way that can fail into a sentence a user can act on.
std::unique_ptr<OIIO::ImageInput> open_input(const std::string& path) {
    std::error_code ec;
    if (!fs::exists(path, ec))
        throw IoError("image file not found: '" + path + "'; check the path");
    if (fs::is_directory(path, ec))
        throw IoError("'" + path + "' is a folder, not an image file");
    if (fs::file_size(path, ec) == 0)
        throw IoError("image file '" + path + "' is empty (0 bytes); re-export it");
    auto in = OIIO::ImageInput::open(path);
    if (!in)
        throw IoError("cannot read '" + path + "' as an image: " +
                      last_oiio_error("unknown or damaged format") +
                      "; check that the file is complete and of a supported format (EXR, HDR, PNG, TIFF, video)");
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
        throw IoError("image '" + path + "' has zero size (" + std::to_string(spec.width) + "x" +
                      std::to_string(spec.height) + ", " + std::to_string(spec.nchannels) +
                      " channels); nothing to read");
    return in;
}

int count_subimages(OIIO::ImageInput& in) {
    const int declared = in.spec().get_int_attribute("oiio:subimages", 0);
    if (declared > 0)
        return declared;
    int n = 1;
    while (in.seek_subimage(n, 0))
        ++n;
    in.seek_subimage(0, 0);
    return n;
}

std::string recorded_colorspace(const OIIO::ImageSpec& spec) {
    for (const char* key : {"penumbra:colorspace", "oiio:ColorSpace"}) {
        std::string value = spec.get_string_attribute(key);
        if (!value.empty())
            return value;
    }
    return {};
}

// Indices of the channels that become R, G, B (see the header's table).
std::array<int, 3> rgb_channels(const OIIO::ImageSpec& spec) {
    if (spec.nchannels <= 2)
        return {0, 0, 0};
    std::array<int, 3> picked{0, 1, 2};
    const char* names[3] = {"R", "G", "B"};
    for (int k = 0; k < 3; ++k) {
        auto it = std::find(spec.channelnames.begin(), spec.channelnames.end(), names[k]);
        if (it == spec.channelnames.end())
            return {0, 1, 2};
        picked[k] = static_cast<int>(it - spec.channelnames.begin());
    }
    return picked;
}

}  // namespace

ImageInfo read_image_info(const std::string& path) {
    auto in = open_input(path);
    const OIIO::ImageSpec& spec = in->spec();
    ImageInfo info;
    info.width = spec.width;
    info.height = spec.height;
    info.file_channels = spec.nchannels;
    info.format = in->format_name();
    info.colorspace = recorded_colorspace(spec);
    info.subimages = count_subimages(*in);
    return info;
}

Image read_image(const std::string& path, int subimage) {
    auto in = open_input(path);
    if (subimage < 0 || (subimage > 0 && !in->seek_subimage(subimage, 0)))
        throw IoError("'" + path + "' has no frame " + std::to_string(subimage) + " (it has " +
                      std::to_string(count_subimages(*in)) + ")");
    const OIIO::ImageSpec spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0)
        throw IoError("frame " + std::to_string(subimage) + " of '" + path + "' has zero size");
    const int nc = spec.nchannels;
    const auto rgb = rgb_channels(spec);
    const std::string damaged = "cannot read the pixels of '" + path + "': ";
    Image image(spec.width, spec.height, 3);
    if (rgb == std::array<int, 3>{0, 1, 2}) {
        // R, G, B are the first three channels: straight into the image.
        if (!in->read_image(subimage, 0, 0, 3, OIIO::TypeDesc::FLOAT, image.pixels.data()))
            throw IoError(damaged + last_oiio_error("the file is damaged or truncated") +
                          "; the file may be truncated or corrupt, re-export it");
        return image;
    }
    std::vector<float> raw(static_cast<std::size_t>(spec.width) * spec.height * nc);
    if (!in->read_image(subimage, 0, 0, nc, OIIO::TypeDesc::FLOAT, raw.data()))
        throw IoError(damaged + last_oiio_error("the file is damaged or truncated") +
                      "; the file may be truncated or corrupt, re-export it");

    const std::size_t n = image.pixel_count();
    for (std::size_t p = 0; p < n; ++p)
        for (int c = 0; c < 3; ++c)
            image.pixels[p * 3 + c] = raw[p * nc + rgb[c]];
    return image;
}

namespace {

void write_with_oiio(const std::string& path, const Image& image, OIIO::ImageSpec spec,
                     const std::string& colorspace) {
    if (image.empty() || image.pixels.size() != image.pixel_count() * image.channels)
        throw ArgumentError("cannot write '" + path + "': the image is empty (" +
                            std::to_string(image.width) + "x" + std::to_string(image.height) + ")");
    if (!colorspace.empty()) {
        spec.attribute("oiio:ColorSpace", colorspace);
        spec.attribute("penumbra:colorspace", colorspace);
    }
    write_file_durably(path, [&](const std::string& temporary) {
        auto out = OIIO::ImageOutput::create(temporary);
        if (!out)
            throw IoError("cannot write '" + path + "': " + last_oiio_error("unsupported file extension"));
        if (!out->open(temporary, spec))
            throw IoError("cannot write '" + path + "': " + out->geterror());
        const bool ok = out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data());
        const bool closed = out->close();
        if (!ok || !closed)
            throw IoError("cannot write '" + path + "': " + out->geterror() + " (disk full or no permission?)");
    });
}

}  // namespace

void write_exr(const std::string& path, const Image& image, ExrPrecision precision,
               const std::string& colorspace) {
    OIIO::ImageSpec spec(image.width, image.height, image.channels,
                         precision == ExrPrecision::half ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT);
    spec.attribute("compression", "zip");
    write_with_oiio(path, image, spec, colorspace);
}

void write_png16(const std::string& path, const Image& image, const std::string& colorspace) {
    OIIO::ImageSpec spec(image.width, image.height, image.channels, OIIO::TypeDesc::UINT16);
    // OpenImageIO quantizes float to uint16 with clamping to [0, 1].
    write_with_oiio(path, image, spec, colorspace);
}

}  // namespace penumbra
