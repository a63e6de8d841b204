// The pre-filtered colour-map lookup of paper Sec. 4.2 (Eq. 10):
//
//     L(f̄, σ) = ⟨C, N(f̄, σ²)⟩ = (C ∗ N(0, σ²))(f̄),
//
// the average colour of a colour map C driven by values distributed as a
// Gaussian with mean f̄ and standard deviation σ. C is clamped outside [0, 1]
// (ColorMap), so a mean near an end and a spread reaching past it are both
// exact. The convolution is done in closed form: over each piece of a
// piecewise-linear (or piecewise-constant) map the Gaussian integral is a
// combination of Φ (through erfc) and φ, written so that it neither cancels
// at huge σ nor underflows at tiny σ. σ = 0 is the map itself; σ → ∞ tends to
// (C(0) + C(1)) / 2, the mean of the clamped map under an infinitely wide
// Gaussian.
//
// The table: an Image (width, height, channels) whose column x holds
// f̄ = mean_min + (mean_max − mean_min)·x/(width − 1) and whose row y holds σ
// by the chosen spacing (row 0 is σ = 0). A renderer reads it bilinearly.
#pragma once

#include "common/setting.hpp"
#include "colormap/color_map.hpp"
#include "common/progress.hpp"
#include "image/image.hpp"

namespace penumbra::colormap {

// Exact L(mean, sigma) into out[map.channels]. sigma >= 0 (ArgumentError
// otherwise); sigma = +inf gives the limit (C(0) + C(1)) / 2.
void filtered_color(const ColorMap& map, double mean, double sigma, double* out);

enum class SigmaSpacing {
    linear,     // σ_y = σ_max · t, t = y / (height − 1): the Python contract's spacing
    quadratic,  // σ_y = σ_max · t²: rows packed near σ = 0 where L changes fastest
};

struct LookupSpec {
    int width = 256;
    int height = 256;
    double sigma_max = 0.25;
    static constexpr Range<int> size_range{2, 8192};  // width and height
    static constexpr Range<double> sigma_max_range{1e-6, unbounded};
    double mean_min = 0.0;
    double mean_max = 1.0;
    SigmaSpacing sigma_spacing = SigmaSpacing::linear;

    // Throws ArgumentError: width < 2, height < 2, sigma_max not finite or
    // <= 0, mean range empty or not finite (its width included).
    void validate() const;
    double mean_of_column(double x) const;  // fractional columns allowed
    double sigma_of_row(double y) const;
    double column_of_mean(double mean) const;  // not clamped
    double row_of_sigma(double sigma) const;   // not clamped
};

// The table, float32, row 0 = σ 0. Reports progress every few rows (each row
// is width × knots closed-form evaluations); rows are shared among
// `threads` worker threads (0: the hardware's count).
Image build_lookup(const ColorMap& map, const LookupSpec& spec, const Progress& progress = {}, int threads = 0);

// What a texture unit returns: bilinear interpolation of `table` between
// texel centres, (mean, σ) clamped to the table's ranges (EXTEND). A NaN
// mean or σ is an ArgumentError.
void bilinear_lookup(const Image& table, const LookupSpec& spec, double mean, double sigma, double* out);

struct LookupAccuracy {
    double max_abs_error = 0.0;  // over all probes and channels
    double rms_error = 0.0;
    double worst_mean = 0.0;     // where the largest error was
    double worst_sigma = 0.0;
};

// Bilinear lookup against the exact L at probes_per_axis² points spread over
// the table's ranges (a regular grid offset from the texel grid, so probes
// fall between texels, where interpolation error lives).
LookupAccuracy measure_lookup_accuracy(const ColorMap& map, const LookupSpec& spec, const Image& table,
                                       int probes_per_axis = 300);

}  // namespace penumbra::colormap
