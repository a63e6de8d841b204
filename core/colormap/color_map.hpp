// A 1D colour map C on [0, 1]: the thing a look-dev artist draws with a
// ColorRamp. Stored as knots (position, colour) joined linearly or held
// constant, and extended outside [0, 1] by clamping (C(x) = C(0) for x < 0,
// C(1) for x > 1), as Blender's ColorRamp does. Colours are scene-linear and
// may have any number of channels (RGB, RGBA); values are kept in double.
#pragma once

#include <vector>

namespace penumbra::colormap {

enum class MapInterpolation {
    linear,    // C is continuous and piecewise linear between knots
    constant,  // C(x) = colour of the last knot at or left of x (a step function)
};

struct ColorMap {
    int channels = 0;
    MapInterpolation interpolation = MapInterpolation::linear;
    std::vector<double> positions;  // ascending, in [0, 1], at least one knot
    std::vector<double> colors;     // positions.size() * channels

    int knot_count() const { return static_cast<int>(positions.size()); }
    const double* color(int knot) const { return colors.data() + static_cast<std::size_t>(knot) * channels; }

    // C(x) into out[channels]. Outside the knots the end colours are held
    // (the clamping extension). NaN x gives NaN.
    void evaluate(double x, double* out) const;
};

// The Python contract's map: `count` colours (count x channels, row-major) at
// evenly spaced positions k/(count-1) on [0, 1], joined linearly. count = 1
// is a constant map. Throws ArgumentError for count < 1, channels outside
// 1..4 or a non-finite colour (the message says which sample and channel).
ColorMap color_map_from_samples(const float* colors, int count, int channels);

// Knots at explicit positions (ascending; equal positions allowed: a jump).
// Throws ArgumentError for unsorted/out-of-range positions or non-finite colours.
ColorMap color_map_from_knots(std::vector<double> positions, std::vector<double> colors, int channels,
                              MapInterpolation interpolation);

}  // namespace penumbra::colormap
