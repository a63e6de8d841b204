// Small images for the image tests.
#pragma once

#include <algorithm>

#include "image/image.hpp"

namespace penumbra::testing {

// A w×h RGB image with every channel of every pixel equal to `value`.
inline Image flat(int w, int h, float value) {
    Image image(w, h, 3);
    std::fill(image.pixels.begin(), image.pixels.end(), value);
    return image;
}

}  // namespace penumbra::testing
