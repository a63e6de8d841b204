#include "colormap/color_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "common/error.hpp"

namespace penumbra::colormap {

void ColorMap::evaluate(double x, double* out) const {
    const int n = knot_count();
    if (std::isnan(x)) {
        std::fill(out, out + channels, std::numeric_limits<double>::quiet_NaN());
        return;
    }
    // First knot strictly right of x.
    const auto right = std::upper_bound(positions.begin(), positions.end(), x);
    const int r = static_cast<int>(right - positions.begin());
    if (r == 0 || r == n) {
        const double* c = color(r == 0 ? 0 : n - 1);
        std::copy(c, c + channels, out);
        return;
    }
    const int l = r - 1;
    const double* a = color(l);
    if (interpolation == MapInterpolation::constant) {
        std::copy(a, a + channels, out);
        return;
    }
    const double* b = color(r);
    const double t = (x - positions[l]) / (positions[r] - positions[l]);  // r > l, positions differ
    for (int c = 0; c < channels; ++c)
        out[c] = a[c] + t * (b[c] - a[c]);
}

ColorMap color_map_from_samples(const float* colors, int count, int channels) {
    if (count < 1)
        throw ArgumentError("a colour map needs at least one colour sample");
    if (channels < 1 || channels > 4)
        throw ArgumentError("colour samples must have 1 to 4 channels, not " + std::to_string(channels));
    std::vector<double> positions(count), values(static_cast<std::size_t>(count) * channels);
    for (int k = 0; k < count; ++k) {
        positions[k] = count == 1 ? 0.0 : static_cast<double>(k) / (count - 1);
        for (int c = 0; c < channels; ++c) {
            const float v = colors[static_cast<std::size_t>(k) * channels + c];
            if (!std::isfinite(v))
                throw ArgumentError("colour sample " + std::to_string(k) + " channel " + std::to_string(c) +
                                    " is not a finite number (NaN or Inf)");
            values[static_cast<std::size_t>(k) * channels + c] = v;
        }
    }
    return color_map_from_knots(std::move(positions), std::move(values), channels, MapInterpolation::linear);
}

ColorMap color_map_from_knots(std::vector<double> positions, std::vector<double> colors, int channels,
                              MapInterpolation interpolation) {
    if (channels < 1 || channels > 4)
        throw ArgumentError("colour maps have 1 to 4 channels, not " + std::to_string(channels));
    if (positions.empty())
        throw ArgumentError("a colour map needs at least one knot");
    if (colors.size() != positions.size() * channels)
        throw ArgumentError("colour map: " + std::to_string(colors.size()) + " colour values for " +
                            std::to_string(positions.size()) + " knots of " + std::to_string(channels) + " channels");
    for (std::size_t k = 0; k < positions.size(); ++k) {
        if (!(positions[k] >= 0.0 && positions[k] <= 1.0))
            throw ArgumentError("colour map knot " + std::to_string(k) + " lies outside [0, 1]");
        if (k > 0 && positions[k] < positions[k - 1])
            throw ArgumentError("colour map knots must be in ascending order");
    }
    for (std::size_t i = 0; i < colors.size(); ++i)
        if (!std::isfinite(colors[i]))
            throw ArgumentError("colour map knot " + std::to_string(i / channels) + " has a non-finite colour");
    ColorMap map;
    map.channels = channels;
    map.interpolation = interpolation;
    map.positions = std::move(positions);
    map.colors = std::move(colors);
    return map;
}

}  // namespace penumbra::colormap
