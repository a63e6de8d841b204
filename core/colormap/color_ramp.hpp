// Blender's ColorRamp (DNA ColorBand) evaluated exactly as Blender does, so a
// lookup built here filters what the artist sees. Two evaluations exist in
// Blender and both are reproduced:
//   - BKE_colorband_evaluate (blenkernel/intern/colorband.cc): what
//     `ColorRamp.evaluate(position)` returns in Python and what the UI draws;
//     every interpolation (linear, ease, cardinal, B-spline, constant) and
//     colour mode (RGB, HSV, HSL with near/far/cw/ccw hue) in float
//     arithmetic, the same operations in the same order.
//   - what Cycles renders: the ramp baked into a table of 256 entries at
//     positions i/255 (cycles/blender/util.h `colorramp_to_array`), read by
//     `rgb_ramp_lookup` with linear interpolation between entries, or, for
//     the constant mode, the entry at floor(255 x) (no interpolation).
// Colours are scene-linear (Blender stores ColorRamp colours linear).
#pragma once

#include <array>
#include <vector>

#include "colormap/color_map.hpp"

namespace penumbra::colormap {

enum class RampInterpolation { linear, ease, cardinal, b_spline, constant };
enum class RampColorMode { rgb, hsv, hsl };
enum class RampHueInterpolation { near, far, cw, ccw };

struct RampStop {
    float position = 0.0f;
    std::array<float, 4> color{0.0f, 0.0f, 0.0f, 1.0f};  // RGBA, scene-linear
};

struct ColorRamp {
    std::vector<RampStop> stops;  // any order: evaluation sorts a copy as Blender keeps them sorted
    RampInterpolation interpolation = RampInterpolation::linear;
    RampColorMode color_mode = RampColorMode::rgb;
    RampHueInterpolation hue_interpolation = RampHueInterpolation::near;
};

// BKE_colorband_evaluate. The ramp must have 1..32 stops with finite colours
// and positions in [0, 1] (ArgumentError otherwise; see validate_ramp).
std::array<float, 4> evaluate_ramp(const ColorRamp& ramp, float position);

// Throws ArgumentError naming the first problem: no stops, more than 32,
// a NaN/Inf colour or position, a position outside [0, 1].
void validate_ramp(const ColorRamp& ramp);

enum class RampSampling {
    // What the renderer renders: `table_size` entries at i/(table_size - 1),
    // linear between them (the constant mode: a step per entry). The default
    // for lookups, so a filtered lookup converges to the plain ramp's render.
    cycles_table,
    // BKE_colorband_evaluate itself: the linear RGB mode and the constant mode
    // are used knot for knot (exact); ease, cardinal, B-spline and HSV/HSL are
    // sampled at `dense_samples` evenly spaced positions and joined linearly
    // (error reported by ramp_sampling_error).
    exact,
};

// The ramp as a ColorMap with `channels` (3: RGB, 4: RGBA) channels.
// Entries of the table a renderer evaluates a ColorRamp through, as measured
// (docs/colormap.md, "The ramp the renderer renders"): Cycles in Blender 3.x
// samples RAMP_TABLE_SIZE = 256 entries at i/255; EEVEE in every version and
// Cycles in 4.5 and 5.2 use Blender's own colour-band table, 257 entries at
// i/256. A constant ramp's steps move by up to one entry between the two.
inline constexpr int cycles_3x_ramp_table_size = 256;
inline constexpr int colorband_ramp_table_size = 257;

ColorMap ramp_to_color_map(const ColorRamp& ramp, RampSampling sampling, int channels = 4,
                           int dense_samples = 1024, int table_size = cycles_3x_ramp_table_size);

// Largest |map(x) - evaluate_ramp(x)| over `probes` evenly spaced positions
// (a measurement of the dense sampling error, for the docs and tests).
double ramp_sampling_error(const ColorRamp& ramp, const ColorMap& map, int probes = 100003);

}  // namespace penumbra::colormap
