#include "image/image.hpp"

#include <cmath>

namespace penumbra {

namespace {
template <bool Fix>
PixelDefects scan(std::vector<float>& values, bool clamp_negative) {
    PixelDefects d;
    for (float& v : values) {
        if (std::isnan(v)) {
            ++d.nan;
            if constexpr (Fix) v = 0.0f;
        } else if (std::isinf(v)) {
            ++d.inf;
            if constexpr (Fix) v = 0.0f;
        } else if (v < 0.0f) {
            ++d.negative;
            if constexpr (Fix) if (clamp_negative) v = 0.0f;
        }
    }
    return d;
}
}  // namespace

PixelDefects count_defects(const Image& image) {
    return scan<false>(const_cast<std::vector<float>&>(image.pixels), false);
}

PixelDefects sanitize(Image& image, bool clamp_negative) {
    return scan<true>(image.pixels, clamp_negative);
}

}  // namespace penumbra
