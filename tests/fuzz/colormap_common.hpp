// Pieces shared by the colour-map harnesses: a lookup spec from fuzz bytes
// and the one property every filtered colour has.
#pragma once

#include <algorithm>
#include <cmath>

#include "colormap/color_map.hpp"
#include "colormap/lookup.hpp"
#include "fuzz_util.hpp"

namespace penumbra::fuzz {

// A small table (2..12 texels a side, so an input stays fast) with any
// sigma_max and mean range, including the invalid ones validate() refuses.
inline colormap::LookupSpec take_spec(Bytes& in) {
    colormap::LookupSpec spec;
    spec.width = in.in_range(0, 12);
    spec.height = in.in_range(0, 12);
    spec.sigma_max = in.take<double>();
    spec.mean_min = in.take<double>();
    spec.mean_max = in.take<double>();
    spec.sigma_spacing = in.byte() & 1 ? colormap::SigmaSpacing::quadratic : colormap::SigmaSpacing::linear;
    return spec;
}

// L(mean, σ) is an average of C's values (C convolved with a Gaussian, C
// clamped outside [0, 1]), so each channel lies within C's range.
inline void check_within_map_range(const colormap::ColorMap& map, const double* value, const char* what) {
    for (int c = 0; c < map.channels; ++c) {
        double lo = INFINITY, hi = -INFINITY;
        for (int k = 0; k < map.knot_count(); ++k) {
            lo = std::min(lo, map.color(k)[c]);
            hi = std::max(hi, map.color(k)[c]);
        }
        const double slack = 1e-6 * std::max(1.0, std::max(std::fabs(lo), std::fabs(hi)));
        penumbra_fuzz_check(value[c] >= lo - slack && value[c] <= hi + slack,
                            std::string(what) + " lies outside the colour map's range");
    }
}


// Builds the table for `map` and checks every texel and a few look-ups.
inline void check_lookup(const colormap::ColorMap& map, const colormap::LookupSpec& spec, Bytes& in) {
    const Image table = colormap::build_lookup(map, spec, {}, 1);
    penumbra_fuzz_check(table.width == spec.width && table.height == spec.height && table.channels == map.channels &&
                            table.pixels.size() == table.pixel_count() * std::size_t(table.channels),
                        "build_lookup returned a table of the wrong size");
    std::vector<double> value(map.channels);
    for (std::size_t p = 0; p < table.pixel_count(); ++p) {
        for (int c = 0; c < map.channels; ++c) value[c] = table.pixels[p * table.channels + c];
        check_within_map_range(map, value.data(), "a lookup table texel");
    }
    for (int probe = 0; probe < 4; ++probe) {
        const double mean = in.take<double>(), sigma = in.take<double>();
        colormap::bilinear_lookup(table, spec, mean, sigma, value.data());
        check_within_map_range(map, value.data(), "a bilinear look-up");
        if (!(sigma >= 0.0)) continue;
        colormap::filtered_color(map, mean, sigma, value.data());
        check_within_map_range(map, value.data(), "filtered_color");
    }
    colormap::measure_lookup_accuracy(map, spec, table, 3);
}

}  // namespace penumbra::fuzz
