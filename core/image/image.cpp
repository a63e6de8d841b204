#include "image/image.hpp"

#include <cmath>

namespace penumbra {

namespace {
// Classifies every value; `fix` (if given) is applied to the defective ones.
template <typename Fix>
PixelDefects scan(const std::vector<float>& values, Fix&& fix) {
    PixelDefects d;
    for (std::size_t i = 0; i < values.size(); ++i) {
        const float v = values[i];
        if (std::isnan(v)) {
            ++d.nan;
            fix(i, false);
        } else if (std::isinf(v)) {
            ++d.inf;
            fix(i, false);
        } else if (v < 0.0f) {
            ++d.negative;
            fix(i, true);
        }
    }
    return d;
}
}  // namespace

PixelDefects count_defects(const Image& image) {
    return scan(image.pixels, [](std::size_t, bool) {});
}

PixelDefects sanitize(Image& image, bool clamp_negative) {
    return scan(image.pixels, [&](std::size_t i, bool negative) {
        if (!negative || clamp_negative)
            image.pixels[i] = 0.0f;
    });
}

}  // namespace penumbra
