#include "lights/frame_lights.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <numbers>
#include <string>
#include <utility>

#include <Eigen/Geometry>

#include "common/error.hpp"
#include "lights/exact_irradiance.hpp"
#include "lights/region_assignment.hpp"
#include "lights/region_kernels.hpp"
#include "lights/irradiance_fit.hpp"
#include "lights/sun_irradiance.hpp"
#include "common/parallel.hpp"
#include "sh/point_sets.hpp"

namespace penumbra::lights {
namespace {

constexpr double pi = std::numbers::pi;

double luma(const std::array<double, 3>& y, const Eigen::Vector3d& rgb) {
    return y[0] * rgb[0] + y[1] * rgb[1] + y[2] * rgb[2];
}

void check_light_count(const EnvironmentMap& map, const LightOptions& options) {
    const std::size_t cells = std::size_t(map.width) * map.height;
    if (options.count < 1)
        throw ArgumentError("the light count must be at least 1, got " + std::to_string(options.count));
    if (std::size_t(options.count) > cells)
        throw ArgumentError("the light count " + std::to_string(options.count) + " exceeds the " +
                            std::to_string(cells) + " pixels of the working map (" + std::to_string(map.width) +
                            "x" + std::to_string(map.height) + "); use at most that many lights");
}

// Light k at the sampler's image of point k (Cranley–Patterson shifted);
// returns the samples (direction and grid cell).
std::vector<Sample> place_lights(const Sampler& sampler, const LightOptions& options, FrameLights& out) {
    const int n = options.count;
    auto points = sample_points(n, options.blue_noise);
    if (!options.point_shift.isZero())
        for (auto& p : points)
            p = Eigen::Vector2d(p.x() + options.point_shift.x() - std::floor(p.x() + options.point_shift.x()),
                                p.y() + options.point_shift.y() - std::floor(p.y() + options.point_shift.y()));
    out.lights.resize(n);
    std::vector<Sample> samples(n);
    for (int k = 0; k < n; ++k) {
        samples[k] = sampler.sample(points[k].x(), points[k].y());
        out.lights[k].index = k;
        out.lights[k].sample_direction = samples[k].direction;
        out.lights[k].direction = samples[k].direction;
    }
    return samples;
}

// The paper's equal split; colour from the cell the sample fell in.
void equal_power(const EnvironmentMap& map, const LuminanceDistribution& dist, const std::vector<Sample>& samples,
                 const LightOptions& options, FrameLights& out) {
    const int n = options.count;
    const double share = out.total_power / n;
    for (int k = 0; k < n; ++k) {
        const float* p = map.pixel(samples[k].row, samples[k].column);
        Eigen::Vector3d chroma(p[0], p[1], p[2]);
        const double y = luma(options.luminance, chroma);
        chroma = y > 0.0 ? Eigen::Vector3d(chroma / y) : Eigen::Vector3d::Ones();
        Light& l = out.lights[k];
        l.rgb = share * chroma;
        l.power = share;
        // A light covers about 1/(N p(ω)) steradians: RMS radius of that disc.
        const double w = dist.weight[std::size_t(samples[k].row) * map.width + samples[k].column];
        const double omega_cell = map.solid_angle(samples[k].row);
        const double density = dist.total > 0.0 && omega_cell > 0.0 ? w / (omega_cell * dist.total) : 0.0;
        const double cover = density > 0.0 ? 1.0 / (n * density) : 4.0 * pi / n;
        l.spread = std::min(pi / 4, std::sqrt(std::min(cover, 2 * pi) / pi) / std::sqrt(2.0));
    }
}

// Cells [begin, end) of `row` that went to `light` (black cells among them
// went to none).
struct CellRun {
    int row, begin, end, light;
};

// What region mode gathers per light: Σ L Ω (RGB), the luminance-weighted
// direction moment and Σ Y·Ω, the light each cell went to (−1: black), and
// the runs of cells behind the sums, in the order they were added.
struct Regions {
    std::vector<Eigen::Vector3d> rgb, moment;
    std::vector<double> y;
    std::unique_ptr<int[]> owner;  // every cell written by the assignment: not zeroed first
    std::vector<CellRun> runs;
    std::vector<std::size_t> row_runs;  // runs[row_runs[r] ..] are row r's (height + 1 entries)
    std::shared_ptr<const LatLongGrid> grid;  // the map's cell centres
};

// The cell centres of `map`'s grid. The frames of a video share one grid, so
// the last one is kept: its 2(W + H) sines and cosines cost a few per cent
// of the region step at 360x90.
std::shared_ptr<const LatLongGrid> cell_centres(const EnvironmentMap& map) {
    static std::mutex mutex;
    static std::shared_ptr<const LatLongGrid> last;
    static double last_theta_max = 0.0;
    const std::lock_guard<std::mutex> lock(mutex);
    if (!last || last->width != map.width || last->height != map.height || last_theta_max != map.theta_max()) {
        last = std::make_shared<const LatLongGrid>(map.width, map.height, map.theta_max());
        last_theta_max = map.theta_max();
    }
    return last;
}

// One run of neighbouring cells of a row going to the same light: its share
// of Σ L Ω, Σ Y·Ω·ω and Σ Y·Ω. Ω and θ are the row's, so only φ varies along
// the run: Σ Y·Ω·ω = (sin θ Σ w cos φ, sin θ Σ w sin φ, cos θ Σ w).
struct RunSum {
    CellRun run;
    Eigen::Vector3d rgb, moment;
    double y;
};

// Cells [c0, c1) of row r as the SIMD kernels take them (region_kernels.hpp).
detail::RowRun row_run(const EnvironmentMap& map, const LuminanceDistribution& dist, const LatLongGrid& grid, int r,
                       int c0, int c1) {
    const std::size_t first = std::size_t(r) * map.width + std::size_t(c0);
    return {map.rgb.data() + 3 * first,
            dist.weight.data() + first,
            grid.cos_phi.data() + c0,
            grid.sin_phi.data() + c0,
            grid.sin_theta[std::size_t(r)],
            grid.cos_theta[std::size_t(r)],
            std::size_t(c1 - c0),
            std::size_t(map.width) * map.height - first};
}

bool black(const float* p) { return p[0] <= 0.0f && p[1] <= 0.0f && p[2] <= 0.0f; }

// The run's sums cell by cell, leaving out black cells: for a map that is
// not sanitized (negative values), where adding everything would not do.
detail::RunSums lit_cell_sums(const EnvironmentMap& map, const LuminanceDistribution& dist, const LatLongGrid& grid,
                              int r, int c0, int c1) {
    detail::RunSums s{{0.0, 0.0, 0.0}, 0.0, 0.0, 0.0, false, true};
    for (int c = c0; c < c1; ++c) {
        const float* p = map.pixel(r, c);
        if (black(p)) continue;
        const double w = dist.weight[std::size_t(r) * map.width + c];
        for (int ch = 0; ch < 3; ++ch) s.rgb[ch] += p[ch];
        s.w += w;
        s.w_cos += w * grid.cos_phi[std::size_t(c)];
        s.w_sin += w * grid.sin_phi[std::size_t(c)];
    }
    return s;
}

// Rows [b, e) of the map, whose cells' nearest samples are in `owner` (black
// cells become −1 there): one RunSum per run of cells with the same nearest
// sample, in scan order, summed on SIMD lanes (region_kernels.hpp).
void sum_rows(const EnvironmentMap& map, const LuminanceDistribution& dist, const LatLongGrid& grid, int b, int e,
              int* owner, std::vector<RunSum>& out) {
    for (int r = b; r < e; ++r) {
        const std::size_t first = std::size_t(r) * map.width;
        int* row = owner + first;
        const double omega = map.solid_angle(r);
        const double st = grid.sin_theta[std::size_t(r)], ct = grid.cos_theta[std::size_t(r)];
        for (int c = 0; c < map.width;) {
            const int k = row[c];
            int end = c + 1;
            while (end < map.width && row[end] == k) ++end;
            detail::RunSums s = detail::run_sums(row_run(map, dist, grid, r, c, end));
            // A black cell belongs to no light; every black cell has weight 0.
            const bool maybe_black = s.unweighted || s.negative;
            if (s.negative) s = lit_cell_sums(map, dist, grid, r, c, end);
            out.push_back({{r, c, end, k}, omega * Eigen::Vector3d(s.rgb[0], s.rgb[1], s.rgb[2]),
                           Eigen::Vector3d(st * s.w_cos, st * s.w_sin, ct * s.w), s.w});
            if (maybe_black)
                for (int j = c; j < end; ++j)
                    if (black(map.pixel(r, j))) row[j] = -1;
            c = end;
        }
    }
}

// Every lit cell goes to its nearest sample (region_assignment.hpp: the same
// assignment as a search over every sample). Runs and their sums per block
// of rows, added in block and run order: the same result on any number of
// threads.
Regions gather_regions(const EnvironmentMap& map, const LuminanceDistribution& dist,
                       const std::vector<Sample>& samples, const ParallelOptions& rows) {
    const int n = int(samples.size());
    std::vector<Eigen::Vector3d> directions(n);
    for (int k = 0; k < n; ++k) directions[k] = samples[k].direction;
    const Sites sites(directions);
    Regions total{std::vector<Eigen::Vector3d>(n, Eigen::Vector3d::Zero()),
                  std::vector<Eigen::Vector3d>(n, Eigen::Vector3d::Zero()),
                  std::vector<double>(n, 0.0),
                  std::unique_ptr<int[]>(new int[std::size_t(map.width) * map.height]),
                  {},
                  std::vector<std::size_t>(std::size_t(map.height) + 1, 0),
                  cell_centres(map)};
    const LatLongGrid& grid = *total.grid;
    std::vector<std::vector<RunSum>> runs(block_count(std::size_t(map.height), rows.block));
    parallel_blocks(std::size_t(map.height), rows, [&](std::size_t block, std::size_t b, std::size_t e) {
        int* owner = total.owner.get() + b * std::size_t(map.width);
        assign_nearest(grid, sites, int(b), int(e), owner);
        runs[block].reserve((e - b) * 32);  // about as many runs per row as at 360x90 with 300 lights
        sum_rows(map, dist, grid, int(b), int(e), total.owner.get(), runs[block]);
    });
    std::size_t count = 0;
    for (const auto& block : runs) count += block.size();
    total.runs.reserve(count);
    for (const auto& block : runs)
        for (const RunSum& sum : block) {
            const int k = sum.run.light;
            total.rgb[k] += sum.rgb;
            total.moment[k] += sum.moment;
            total.y[k] += sum.y;
            if (sum.run.begin == 0) total.row_runs[std::size_t(sum.run.row)] = total.runs.size();
            total.runs.push_back(sum.run);
        }
    total.row_runs[std::size_t(map.height)] = total.runs.size();
    return total;
}

// Spread: RMS angle of each region about its light's direction. Row by row
// in parallel (w θ² per cell on SIMD lanes, region_kernels.hpp, each cell
// against its run's light), summed per run in cell order; the runs' sums
// are then added in run order (black cells have weight 0 and add nothing).
void region_spread(const EnvironmentMap& map, const LuminanceDistribution& dist, const Regions& regions,
                   const ParallelOptions& rows, FrameLights& out) {
    const int n = int(out.lights.size());
    const LatLongGrid& grid = *regions.grid;
    std::vector<double> run_sum(regions.runs.size());
    ParallelOptions spread_rows = rows;
    spread_rows.stage = "lights.region_spread";
    parallel_for(std::size_t(map.height), spread_rows, [&](std::size_t b, std::size_t e) {
        // The row's lights per cell, and w θ² per cell; padded for whole SIMD loads and stores.
        const std::size_t padded = std::size_t(map.width) + detail::kMaxLanes;
        std::vector<double> lx(padded, 0.0), ly(padded, 0.0), lz(padded, 0.0), value(padded);
        for (std::size_t r = b; r < e; ++r) {
            const std::size_t first = regions.row_runs[r], last = regions.row_runs[r + 1];
            for (std::size_t i = first; i < last; ++i) {
                const CellRun& run = regions.runs[i];
                const Eigen::Vector3d& l = out.lights[std::size_t(run.light)].direction;
                std::fill(lx.begin() + run.begin, lx.begin() + run.end, l.x());
                std::fill(ly.begin() + run.begin, ly.begin() + run.end, l.y());
                std::fill(lz.begin() + run.begin, lz.begin() + run.end, l.z());
            }
            detail::weighted_squared_angles(row_run(map, dist, grid, int(r), 0, map.width),
                                            {lx.data(), ly.data(), lz.data()}, value.data());
            for (std::size_t i = first; i < last; ++i) {
                const CellRun& run = regions.runs[i];
                // Four partial sums: one chain of dependent adds would cost more than the rest of the pass.
                double sum[4] = {0.0, 0.0, 0.0, 0.0};
                int c = run.begin;
                for (; c + 4 <= run.end; c += 4)
                    for (int k = 0; k < 4; ++k) sum[k] += value[std::size_t(c + k)];
                for (; c < run.end; ++c) sum[0] += value[std::size_t(c)];
                run_sum[i] = (sum[0] + sum[1]) + (sum[2] + sum[3]);
            }
        }
    });
    std::vector<double> second(n, 0.0);
    for (std::size_t i = 0; i < regions.runs.size(); ++i) second[std::size_t(regions.runs[i].light)] += run_sum[i];
    for (int k = 0; k < n; ++k)
        out.lights[k].spread = regions.y[k] > 0.0 ? std::sqrt(second[k] / regions.y[k]) : 0.0;
}

// Region mode: each light carries the power of the cells nearest to it and
// points at their luminance-weighted centroid.
void region_power(const EnvironmentMap& map, const LuminanceDistribution& dist, const std::vector<Sample>& samples,
                  const LightOptions& options, FrameLights& out) {
    // Blocks of at least 16 rows: the assignment's blocks grow with them.
    const ParallelOptions rows{options.threads, std::max<std::size_t>(16, (std::size_t(map.height) + 63) / 64),
                               "lights.region_powers"};
    const Regions regions = gather_regions(map, dist, samples, rows);
    for (std::size_t k = 0; k < out.lights.size(); ++k) {
        Light& l = out.lights[k];
        l.rgb = regions.rgb[k];
        l.power = luma(options.luminance, regions.rgb[k]);
        const double m = regions.moment[k].norm();
        if (m > 1e-300 && regions.y[k] > 0.0) l.direction = regions.moment[k] / m;
    }
    region_spread(map, dist, regions, rows, out);
}

}  // namespace

FrameLights compute_lights(const EnvironmentMap& map, const LuminanceDistribution& dist, const Sampler& sampler,
                           const LightOptions& options) {
    check_light_count(map, options);
    FrameLights out;
    out.total_rgb = integral_rgb(map);
    out.total_power = luma(options.luminance, out.total_rgb);
    const std::vector<Sample> samples = place_lights(sampler, options, out);
    if (options.power == PowerMode::equal)
        equal_power(map, dist, samples, options, out);
    else
        region_power(map, dist, samples, options, out);
    if (options.fit_irradiance && options.count <= LightOptions::max_fitted_lights) {
        IrradianceFitOptions fit;
        fit.sun_model = options.sun_model;
        fit.luminance = options.luminance;
        fit.threads = options.threads;
        fit_irradiance(map, out.lights, fit);
    }
    return out;
}

FrameLights region_lights(const EnvironmentMap& map, const LuminanceDistribution& dist,
                          const std::vector<Eigen::Vector3d>& seeds, const LightOptions& options) {
    if (seeds.empty()) throw ArgumentError("region lights need at least one seed direction");
    FrameLights out;
    out.total_rgb = integral_rgb(map);
    out.total_power = luma(options.luminance, out.total_rgb);
    std::vector<Sample> samples(seeds.size());
    out.lights.resize(seeds.size());
    for (std::size_t k = 0; k < seeds.size(); ++k) {
        samples[k].direction = seeds[k].normalized();
        out.lights[k].index = int(k);
        out.lights[k].sample_direction = samples[k].direction;
        out.lights[k].direction = samples[k].direction;
    }
    LightOptions o = options;
    o.count = int(seeds.size());
    region_power(map, dist, samples, o, out);
    return out;
}

FrameLights compute_lights(const EnvironmentMap& map, const LightOptions& options) {
    const LuminanceDistribution dist = luminance_distribution(map, options.luminance, options.threads);
    const auto sampler = make_sampler(options.sampler, dist);
    return compute_lights(map, dist, *sampler, options);
}

Eigen::MatrixXd irradiance(const std::vector<Light>& lights, const std::vector<Eigen::Vector3d>& normals) {
    Eigen::MatrixXd e = Eigen::MatrixXd::Zero(Eigen::Index(normals.size()), 3);
    for (std::size_t i = 0; i < normals.size(); ++i) {
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (const Light& l : lights) {
            const double c = normals[i].dot(l.direction);
            if (c > 0.0) sum += c * l.rgb;
        }
        e.row(Eigen::Index(i)) = sum.transpose();
    }
    return e;
}

Eigen::MatrixXd exact_irradiance(const EnvironmentMap& map, const std::vector<Eigen::Vector3d>& normals, int threads) {
    return IrradianceReference(map).evaluate(normals, threads);
}

double relative_rmse(const Eigen::MatrixXd& estimate, const Eigen::MatrixXd& reference,
                     const std::array<double, 3>& y) {
    if (estimate.rows() != reference.rows() || estimate.cols() != 3 || reference.cols() != 3)
        throw ArgumentError("relative_rmse needs two (N, 3) irradiance arrays of the same size");
    double num = 0.0, den = 0.0;
    for (Eigen::Index i = 0; i < estimate.rows(); ++i) {
        const double a = y[0] * estimate(i, 0) + y[1] * estimate(i, 1) + y[2] * estimate(i, 2);
        const double b = y[0] * reference(i, 0) + y[1] * reference(i, 1) + y[2] * reference(i, 2);
        num += (a - b) * (a - b);
        den += b * b;
    }
    if (den <= 0.0) return num > 0.0 ? INFINITY : 0.0;
    return std::sqrt(num / den);
}

namespace {

// The map's irradiance on Fibonacci normals over a copy reduced to at most
// 256 columns: the search measures many counts, and irradiance is smooth.
struct ReducedReference {
    std::vector<Eigen::Vector3d> normals;
    Eigen::MatrixXd irradiance;
};

ReducedReference irradiance_reference(const EnvironmentMap& map, int normal_count, int threads) {
    if (normal_count < 1) throw ArgumentError("normal_count must be at least 1");
    MapOptions reduce;
    reduce.projection = map.full_sphere ? Projection::equirectangular : Projection::hemisphere_polar;
    reduce.max_width = 256;
    reduce.threads = threads;
    Image copy(map.width, map.height, 3);
    copy.pixels = map.rgb;
    const EnvironmentMap small = make_environment(copy, reduce);
    ReducedReference r;
    r.normals = sh::fibonacci_sphere(normal_count).directions;
    r.irradiance = exact_irradiance(small, r.normals, threads);
    return r;
}

}  // namespace

int max_lights(SunModel model) {
    return model == SunModel::eevee_legacy ? eevee_legacy_max_lights : std::numeric_limits<int>::max();
}

double rig_error(const EnvironmentMap& map, const std::vector<Light>& lights, SunModel model,
                 const std::array<double, 3>& luminance, int normal_count, int threads) {
    const ReducedReference r = irradiance_reference(map, normal_count, threads);
    return relative_rmse(sun_irradiance(lights, r.normals, model, threads), r.irradiance, luminance);
}

AdaptiveResult adaptive_count(const EnvironmentMap& map, const LightOptions& options, double tolerance,
                              int max_count, int normal_count) {
    if (!(tolerance > 0.0)) throw ArgumentError("the irradiance tolerance must be positive");
    if (max_count < 1) throw ArgumentError("the light budget must be at least 1");
    max_count = std::min(max_count, max_lights(options.sun_model));
    max_count = int(std::min<std::size_t>(std::size_t(max_count), std::size_t(map.width) * map.height));

    const ReducedReference r = irradiance_reference(map, normal_count, options.threads);
    const LuminanceDistribution dist = luminance_distribution(map, options.luminance, options.threads);
    const auto sampler = make_sampler(options.sampler, dist);
    auto error_of = [&](int count) {
        LightOptions o = options;
        o.count = count;
        return relative_rmse(sun_irradiance(compute_lights(map, dist, *sampler, o).lights, r.normals,
                                            options.sun_model, options.threads),
                             r.irradiance, options.luminance);
    };
    int previous = 0;
    for (int count = 1;;) {
        const double e = error_of(count);
        if (e <= tolerance || count >= max_count) {
            if (e > tolerance) return {count, e};
            // Bisect between the last failing and this passing count.
            int lo = previous, hi = count;
            double hi_error = e;
            while (hi - lo > 1) {
                const int mid = (lo + hi) / 2;
                const double m = error_of(mid);
                if (m <= tolerance) { hi = mid; hi_error = m; } else lo = mid;
            }
            return {hi, hi_error};
        }
        previous = count;
        // 1, 2, 3, 4, 6, 8, 12, 16, 24, ...
        const int next = count < 4 ? count + 1 : ((count & (count - 1)) == 0 ? count * 3 / 2 : count * 4 / 3);
        count = std::min(max_count, next);
    }
}

}  // namespace penumbra::lights
