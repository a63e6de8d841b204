// Fuzz harness: opening an image file through our wrappers of OpenImageIO,
// core/image/image_io.cpp (read_image_info, read_image of every frame) and
// the light rig's streaming reader core/lights/map_reader.cpp
// (read_environment, band by band through read_scanlines / read_tiles, in
// every projection).
//
// Input: the file's bytes (the corpus holds real EXR, HDR, PNG, TIFF, JPEG
// files). The file is named with the extension its first bytes announce, as
// a user's file would be; anything else gets ".img", which makes OpenImageIO
// try each of its readers in turn.
#include <cstring>

#include "../fuzz_util.hpp"
#include "image/image_io.hpp"
#include "lights/map_reader.hpp"

using namespace penumbra;

namespace {

const char* extension_for(const std::uint8_t* d, std::size_t n) {
    auto starts = [&](const char* magic, std::size_t len) { return n >= len && std::memcmp(d, magic, len) == 0; };
    if (starts("\x76\x2f\x31\x01", 4)) return ".exr";
    if (starts("#?", 2)) return ".hdr";
    if (starts("\x89PNG", 4)) return ".png";
    if (starts("II*\0", 4) || starts("MM\0*", 4)) return ".tif";
    if (starts("\xff\xd8\xff", 3)) return ".jpg";
    return ".img";
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fuzz::Scratch::get().fresh();
    const std::string path = fuzz::Scratch::get().file(std::string("input") + extension_for(data, size));
    fuzz::write_file(path, data, size);

    ImageInfo info;
    bool opened = false;
    fuzz::expect_only_penumbra_errors([&] {
        info = read_image_info(path);
        opened = true;
    });
    if (!opened) return 0;
    penumbra_fuzz_check(info.width > 0 && info.height > 0 && info.file_channels > 0 && info.subimages >= 1,
                        "read_image_info accepted an image with no pixels");
    for (int frame : {0, info.subimages - 1, info.subimages}) {
        fuzz::expect_only_penumbra_errors([&] {
            const Image image = read_image(path, frame);
            penumbra_fuzz_check(frame < info.subimages, "read_image returned a frame past the last one");
            penumbra_fuzz_check(image.width > 0 && image.height > 0 && image.channels == 3 &&
                                    image.pixels.size() == image.pixel_count() * 3,
                                "read_image returned an image whose size does not match its pixels");
        });
    }
    // Streamed when wider than max_width; tiny bands so the band logic turns
    // over (lat-long: reduced per band; fisheye, mirror ball: look-ups per band).
    for (auto projection : {lights::Projection::equirectangular, lights::Projection::hemisphere_polar,
                            lights::Projection::fisheye, lights::Projection::mirror_ball}) {
        lights::MapOptions options;
        options.projection = projection;
        options.max_width = 4;
        options.threads = 1;
        fuzz::expect_only_penumbra_errors([&] {
            const lights::EnvironmentMap map = lights::read_environment(path, nullptr, "", options, {}, 1);
            penumbra_fuzz_check(map.rgb.size() == std::size_t(map.width) * map.height * 3,
                                "read_environment returned a map whose size does not match its pixels");
        });
    }
    return 0;
}
