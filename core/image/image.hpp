// A float image in memory, the currency of every tool: row-major, interleaved
// channels, row 0 at the TOP (the order OpenImageIO reads files in; Blender's
// own pixel buffers are bottom-up, the add-on flips when it talks to bpy).
#pragma once

#include <cstddef>
#include <vector>

namespace penumbra {

struct Image {
    int width = 0;
    int height = 0;
    int channels = 0;
    std::vector<float> pixels;  // width * height * channels

    Image() = default;
    Image(int w, int h, int c) : width(w), height(h), channels(c),
        pixels(static_cast<std::size_t>(w) * h * c, 0.0f) {}

    bool empty() const { return width <= 0 || height <= 0 || channels <= 0; }
    std::size_t pixel_count() const { return static_cast<std::size_t>(width) * height; }
    float* row(int y) { return pixels.data() + static_cast<std::size_t>(y) * width * channels; }
    const float* row(int y) const { return pixels.data() + static_cast<std::size_t>(y) * width * channels; }
    float& at(int x, int y, int c) { return row(y)[static_cast<std::size_t>(x) * channels + c]; }
    float at(int x, int y, int c) const { return row(y)[static_cast<std::size_t>(x) * channels + c]; }
};

// Counts of pixel values a tool cannot use as light or colour.
struct PixelDefects {
    std::size_t nan = 0;
    std::size_t inf = 0;
    std::size_t negative = 0;
    std::size_t total() const { return nan + inf + negative; }
};

// Counts NaN, ±Inf and negative values without changing anything.
PixelDefects count_defects(const Image& image);

// Replaces NaN and ±Inf by 0 and, if `clamp_negative`, negatives by 0;
// returns what was found. Readers never do this silently: tools call it and
// report the counts, so a user learns their HDR has bad pixels.
PixelDefects sanitize(Image& image, bool clamp_negative);

}  // namespace penumbra
