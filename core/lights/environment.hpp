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
#include <cstddef>
#include <cstdint>
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

// Σ Y·Ω over one RGB input row, each pixel with its own projection's solid
// angle (for source_integral_luminance).
double input_row_luminance(const MapOptions& options, int in_width, int in_height, int row, const float* rgb);

// Throws ArgumentError for a bad max_width, supersampling or fisheye lens.
void check_map_options(const MapOptions& options);

// Building blocks of the fisheye and mirror-ball resampling, shared by
// make_environment (the whole image is one band) and read_environment
// (lights/map_reader.hpp, band by band from the file).
//
// Output cell (r, c) is the mean of ss² bilinear look-ups spread evenly over
// its solid angle. A look-up reads input rows y0 and y0 + 1 and is taken
// while the band that holds y0 is in memory, so the file is read once, top
// to bottom, whatever the projection's random access. Before the first band
// one pass over the look-ups' positions (no pixels) lists, per band, the
// cells with a look-up in it. A cell whose look-ups all fall in one band gets
// exactly its whole-image value; one whose look-ups span bands is summed per
// band in double, so its float value can differ from the whole image's by
// the last bit (tested: at most one ulp).
class BandResampler {
public:
    // Bands of `band_rows` input rows; band_rows ≥ in_height: one band, the
    // whole image, held no index and no partial sums.
    BandResampler(const MapOptions& options, int in_width, int in_height, int band_rows);
    int band_count() const { return band_count_; }
    // Band k needs input rows [first_row(k), end_row(k)): its own rows and
    // the row after them (the bilinear look-ups' lower row).
    int first_row(int band) const { return band * band_rows_; }
    int end_row(int band) const;
    // Takes band k's look-ups from `rows`, RGB input rows [first_row(k),
    // end_row(k)). One band: progress per 64 output rows.
    void add_band(int band, const float* rows, const Progress& progress = {});
    // The working map once every band is in (defects and the source
    // integral are the caller's to fill).
    EnvironmentMap finish();
    // Bytes of the band index and partial sums (excluding the working map).
    std::size_t buffer_bytes() const;

private:
    template <class LookUp>
    void for_each_look_up(int row, int column, LookUp&& look_up) const;
    void add_cells(const std::uint32_t* cells, std::size_t count, const float* rows, int first, int end);
    MapOptions options_;
    int in_width_, in_height_, band_rows_, band_count_, supersampling_;
    EnvironmentMap map_;
    std::vector<double> sub_row_sin_, sub_row_cos_;        // sin θ, cos θ of the look-ups, per (row, sub-row)
    std::vector<double> sub_column_sin_, sub_column_cos_;  // sin φ, cos φ, per (column, sub-column)
    std::vector<std::size_t> band_offsets_;  // per band, its range of band_cells_
    std::vector<std::uint32_t> band_cells_;  // cells (r·width + c) with a look-up in the band
    std::vector<double> sum_;                // per cell, RGB partial sums (several bands only)
};

}  // namespace penumbra::lights
