// The light-rig tool's working form of one frame of lighting: scene-linear
// RGB radiance on a latitude–longitude grid in Blender's World convention
// (lights/mapping.hpp), over the full sphere or the upper hemisphere.
//
// Every input projection becomes this grid:
//   equirectangular, hemisphere_polar  used as they are (or reduced to at most
//       `max_width` columns by exact area-weighted averaging: each output cell
//       is the solid-angle-weighted mean of the input it covers, so the
//       integral ∫ L dω is unchanged);
//   fisheye      resampled to a hemisphere grid (the paper's polar projection,
//                4H × H with H ≈ the image-circle radius in pixels);
//   mirror_ball  resampled to a full-sphere grid (2H × H, H ≈ πR/2),
// both by averaging supersampling² bilinear look-ups per cell.
//
// Bad pixels: NaN and ±Inf become 0, negative values become 0; the counts
// are kept in `defects` so the caller can report them.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "common/progress.hpp"
#include "image/image.hpp"
#include "lights/mapping.hpp"

namespace penumbra::lights {

// Rec. 709 / sRGB luminance weights for Blender's default scene-linear space
// (Linear Rec.709). Pass others for a config whose scene_linear differs.
constexpr std::array<double, 3> rec709_luminance{0.2126, 0.7152, 0.0722};

struct EnvironmentMap {
    int width = 0;
    int height = 0;
    bool full_sphere = true;   // θ ∈ [0, π]; else [0, π/2] (upper hemisphere)
    std::vector<float> rgb;    // width·height·3, row 0 = top (θ = 0)
    PixelDefects defects;      // bad values found in the input (replaced by 0)
    double source_integral_luminance = 0.0;  // Σ Y·Ω over the INPUT pixels (its own Jacobian)

    double theta_max() const;
    double theta_edge(int row) const;          // θ at the top edge of `row`
    double solid_angle(int row) const;         // exact solid angle of a cell in `row`
    Eigen::Vector3d direction(int row, int column) const;  // cell centre
    const float* pixel(int row, int column) const { return rgb.data() + (std::size_t(row) * width + column) * 3; }
};

struct MapOptions {
    Projection projection = Projection::equirectangular;
    FisheyeLens lens;
    // Widest working grid; wider equirectangular input is averaged down
    // (energy-exact). 0 = never reduce. Default 2048: a 16k map becomes
    // 2048×1024 (sub-degree cells) right after it is read.
    int max_width = 2048;
    int supersampling = 3;  // look-ups per cell side when resampling fisheye / mirror ball
    int threads = 0;        // 0 = all cores
};

// `radiance` is scene-linear (convert with ColorConfig first), with 1 (grey),
// 2 (grey, alpha), 3 (RGB) or 4 (RGBA) channels; alpha is ignored. Throws
// ArgumentError for an empty image or a bad option. Reports progress per
// band of 64 output rows.
EnvironmentMap make_environment(const Image& radiance, const MapOptions& options = {},
                                const Progress& progress = {});

// ∫ L(ω) dω per channel and ∫ Y(ω) dω (Y with `luminance` weights), in double.
Eigen::Vector3d integral_rgb(const EnvironmentMap& map);
double integral_luminance(const EnvironmentMap& map, const std::array<double, 3>& luminance = rec709_luminance);

// Rotates an equirectangular image about +z by `angle` radians (the content
// at direction d moves to R_z(angle)·d), with linear interpolation between
// columns: the test-video maker's rotations, exact for multiples of 2π/W.
Image rotate_equirectangular_z(const Image& image, double angle);

// Building blocks of the energy-exact lat-long reduction, shared by
// make_environment (whole image in memory) and read_environment
// (lights/map_reader.hpp, band by band from the file), so both give
// bit-identical maps.
struct LatLongSpans {
    struct Span {
        int first = 0;               // first input column / row covered
        std::vector<double> weight;  // overlap length (columns) or solid-angle share (rows)
    };
    std::vector<Span> columns, rows;  // per output column / row
    LatLongSpans(int in_width, int in_height, int out_width, int out_height, double theta_max);
};

// Output rows [row_begin, row_end) of `out` from the RGB input rows held in
// `band`, whose first row is input row `band_first_row` (every input row
// those output rows cover must be in the band).
void reduce_latlong_rows(const LatLongSpans& spans, const float* band, int band_first_row, int in_width,
                         int row_begin, int row_end, EnvironmentMap& out, int threads);

// Σ Y·Ω over one RGB input row of a lat-long image (for source_integral_luminance).
double latlong_row_luminance(Projection projection, int in_width, int in_height, int row, const float* rgb);

}  // namespace penumbra::lights
