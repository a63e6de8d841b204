#include "lights/region_assignment.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>

#include "common/error.hpp"
#include "common/latlong.hpp"
#include "lights/direction_index.hpp"
#include "lights/region_kernels.hpp"

namespace penumbra::lights {

namespace {

// Added to every candidate bound (chord units): far above the rounding of
// the distances (~1e-15), far below the chord of one cell of any grid the
// tool builds, so the bound can never drop the true nearest direction.
constexpr double margin = 1e-9;

// Up to this many sites a root block's candidates are found by checking
// every site (a few hundred nanoseconds); beyond, through a DirectionIndex.
constexpr std::size_t brute_force_roots = 2048;

// A block with several candidates is not halved again once cells ×
// candidates is at most this: its cells then test the candidates on SIMD
// lanes, cheaper than the bounds of more blocks (measured at 360x90 and
// 1024x512 with 300 lights: 2048 once the cells' test ran four lane vectors
// at a time, 2 % faster than 1024 at 360x90, the same at 1024x512).
constexpr std::size_t leaf_work = 2048;

// Halvings from a root block (at most 64 rows by a quarter of the columns,
// capped at 256) down to single cells take far fewer levels.
constexpr std::size_t max_depth = 64;

}  // namespace

double chord2(const Eigen::Vector3d& site, const Eigen::Vector3d& x) {
    const double dx = site.x() - x.x(), dy = site.y() - x.y(), dz = site.z() - x.z();
    return (dx * dx + dy * dy) + dz * dz;
}

Sites::Sites(const std::vector<Eigen::Vector3d>& directions) : directions_(directions) {
    if (directions.empty()) throw ArgumentError("a region assignment needs at least one direction");
    const std::size_t n = directions.size();
    index_.resize(n);
    x_.resize(n);
    y_.resize(n);
    z_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        index_[i] = int(i);
        x_[i] = directions[i].x();
        y_[i] = directions[i].y();
        z_[i] = directions[i].z();
    }
    if (n > brute_force_roots) search_ = std::make_unique<DirectionIndex>(directions_);
}

Sites::~Sites() = default;

namespace {

// A block's candidates: site indices (ascending) and their coordinates side
// by side, so the loops over them run on whole SIMD registers. The storage
// only grows, in powers of two, and is never copied or cleared (every block
// writes what it uses): `count` says how much of it is in use.
struct Candidates {
    std::unique_ptr<int[]> index;
    std::unique_ptr<double[]> x, y, z;
    std::size_t capacity = 0, count = 0;
    detail::Points points() const { return {x.get(), y.get(), z.get()}; }
    void reserve(std::size_t n) {
        if (capacity >= n) return;
        capacity = std::bit_ceil(std::max<std::size_t>(n, 64));
        index = std::make_unique_for_overwrite<int[]>(capacity);
        x = std::make_unique_for_overwrite<double[]>(capacity);
        y = std::make_unique_for_overwrite<double[]>(capacity);
        z = std::make_unique_for_overwrite<double[]>(capacity);
    }
};

}  // namespace

class Assigner {
public:
    Assigner(const LatLongGrid& grid, const Sites& sites, int row_begin, int* owner)
        : grid_(grid), sites_(sites), row_begin_(row_begin), owner_(owner), levels_(max_depth),
          row_angle_(grid.height > 1 ? std::abs(std::acos(grid.cos_theta[1]) - std::acos(grid.cos_theta[0])) : 1.0),
          column_angle_(2.0 * std::numbers::pi / std::max(grid.width, 1)) {}

    // A block no wider than a quarter of the grid (so the corner cells bound
    // its radius, below): candidates from every site or from the index.
    void root(int r0, int r1, int c0, int c1) {
        if (!sites_.search_) {
            const detail::Points all{sites_.x_.data(), sites_.y_.data(), sites_.z_.data()};
            return block(r0, r1, c0, c1, all, sites_.index_.data(), sites_.size(), 0);
        }
        const Eigen::Vector3d centre = grid_.direction((r0 + r1 - 1) / 2, (c0 + c1 - 1) / 2);
        const int near = sites_.search_->nearest(centre);
        const double bound = std::sqrt(chord2(sites_.directions_[std::size_t(near)], centre)) +
                             2.0 * radius(r0, r1, c0, c1, centre) + margin;
        const double angle = bound >= 2.0 ? std::numbers::pi : 2.0 * std::asin(0.5 * bound) + margin;
        sites_.search_->within(centre, angle, within_);
        root_.reserve(within_.size());
        root_.count = within_.size();
        for (std::size_t k = 0; k < within_.size(); ++k) {
            const std::size_t i = std::size_t(within_[k]);
            root_.index[k] = within_[k];
            root_.x[k] = sites_.x_[i];
            root_.y[k] = sites_.y_[i];
            root_.z[k] = sites_.z_[i];
        }
        block(r0, r1, c0, c1, root_.points(), root_.index.get(), root_.count, 0);
    }

private:
    // Chord from the centre cell to the farthest cell of the block. For a
    // block spanning at most π/2 in azimuth the farthest cell is a corner:
    // along a row the chord grows with |Δφ|, along a column it is
    // 2 − 2R cos(θ − α), whose maximum over an interval is at an end.
    double radius(int r0, int r1, int c0, int c1, const Eigen::Vector3d& centre) const {
        double far = 0.0;
        for (const int r : {r0, r1 - 1})
            for (const int c : {c0, c1 - 1}) far = std::max(far, chord2(grid_.direction(r, c), centre));
        return std::sqrt(far);
    }

    // The largest sin θ over rows [r0, r1): at the row nearest the equator.
    double widest_sine(int r0, int r1) const {
        if (grid_.cos_theta[std::size_t(r0)] >= 0.0 && grid_.cos_theta[std::size_t(r1 - 1)] <= 0.0) return 1.0;
        return std::max(grid_.sin_theta[std::size_t(r0)], grid_.sin_theta[std::size_t(r1 - 1)]);
    }

    void block(int r0, int r1, int c0, int c1, detail::Points parent, const int* parent_index, std::size_t n,
               std::size_t depth) {
        if (depth >= levels_.size()) throw Error("internal: region assignment recursed too deep");
        const Eigen::Vector3d centre = grid_.direction((r0 + r1 - 1) / 2, (c0 + c1 - 1) / 2);
        // The candidates that can be nearest somewhere in the block.
        if (distance_.size() < n) distance_.resize(n);
        const double nearest = detail::chord2_to(parent, n, centre.x(), centre.y(), centre.z(), distance_.data());
        const double bound = std::sqrt(nearest) + 2.0 * radius(r0, r1, c0, c1, centre) + margin;
        const double bound2 = bound * bound;
        Candidates& kept = levels_[depth];
        kept.reserve(n);
        const std::size_t m = detail::keep_within(parent, parent_index, n, distance_.data(), bound2, kept.x.get(),
                                                  kept.y.get(), kept.z.get(), kept.index.get());
        kept.count = m;

        if (m == 1) {
            for (int r = r0; r < r1; ++r) std::fill(cell(r, c0), cell(r, c1), kept.index[0]);
            return;
        }
        const int rows = r1 - r0, columns = c1 - c0;
        if (std::size_t(rows) * std::size_t(columns) * m <= leaf_work || rows * columns <= 4)
            return cells(r0, r1, c0, c1, kept);
        // Halve across the side that spans the wider angle.
        const double tall = rows * row_angle_;
        const double wide = columns * column_angle_ * widest_sine(r0, r1);
        if (columns == 1 || (rows > 1 && tall >= wide)) {
            const int rm = r0 + rows / 2;
            block(r0, rm, c0, c1, kept.points(), kept.index.get(), m, depth + 1);
            block(rm, r1, c0, c1, kept.points(), kept.index.get(), m, depth + 1);
        } else {
            const int half = c0 + columns / 2;
            block(r0, r1, c0, half, kept.points(), kept.index.get(), m, depth + 1);
            block(r0, r1, half, c1, kept.points(), kept.index.get(), m, depth + 1);
        }
    }

    int* cell(int r, int c) const { return owner_ + std::size_t(r - row_begin_) * grid_.width + c; }

    // Every cell of the block tests every candidate (region_kernels.hpp), in
    // ascending order (strict <: the lowest index wins a tie), in chord2's
    // arithmetic.
    void cells(int r0, int r1, int c0, int c1, const Candidates& candidates) {
        const std::size_t w = std::size_t(c1 - c0), count = std::size_t(r1 - r0) * w;
        if (cx_.size() < count) {
            cx_.resize(count);
            cy_.resize(count);
            cz_.resize(count);
            nearest_.resize(count);
        }
        for (int r = r0; r < r1; ++r) {
            const std::size_t j = std::size_t(r - r0) * w;
            const double st = grid_.sin_theta[std::size_t(r)], ct = grid_.cos_theta[std::size_t(r)];
            for (std::size_t k = 0; k < w; ++k) {
                cx_[j + k] = st * grid_.cos_phi[std::size_t(c0) + k];
                cy_[j + k] = st * grid_.sin_phi[std::size_t(c0) + k];
                cz_[j + k] = ct;
            }
        }
        detail::nearest_candidates(candidates.points(), candidates.index.get(), candidates.count,
                                   {cx_.data(), cy_.data(), cz_.data()}, count, nearest_.data());
        for (int r = r0; r < r1; ++r) std::copy_n(nearest_.data() + std::size_t(r - r0) * w, w, cell(r, c0));
    }

    const LatLongGrid& grid_;
    const Sites& sites_;
    int row_begin_;
    int* owner_;
    Candidates root_;
    std::vector<int> within_;
    std::vector<Candidates> levels_;  // candidates kept at each depth of the halving
    std::vector<double> distance_, cx_, cy_, cz_;
    std::vector<int> nearest_;
    double row_angle_, column_angle_;  // Δθ, Δφ of one cell
};

LatLongGrid::LatLongGrid(int w, int h, double theta_max) : width(w), height(h) {
    sin_theta.resize(std::size_t(std::max(h, 0)));
    cos_theta.resize(sin_theta.size());
    // Zeros past the last column: SIMD loops read whole registers (region_kernels.hpp).
    cos_phi.assign(std::size_t(std::max(w, 0)) + detail::kMaxLanes, 0.0);
    sin_phi.assign(cos_phi.size(), 0.0);
    // The same calls as latlong::pixel_direction, so the products match it bit for bit.
    for (int r = 0; r < h; ++r) {
        const double theta = latlong::theta_of_y(r + 0.5, h, theta_max);
        sin_theta[std::size_t(r)] = std::sin(theta);
        cos_theta[std::size_t(r)] = std::cos(theta);
    }
    for (int c = 0; c < w; ++c) {
        const double phi = latlong::phi_of_x(c + 0.5, w);
        cos_phi[std::size_t(c)] = std::cos(phi);
        sin_phi[std::size_t(c)] = std::sin(phi);
    }
}

void assign_nearest(const LatLongGrid& grid, const Sites& sites, int row_begin, int row_end, int* owner) {
    if (row_begin < 0 || row_end > grid.height || row_begin > row_end)
        throw ArgumentError("assign_nearest: rows outside the grid");
    Assigner assigner(grid, sites, row_begin, owner);
    // Root blocks at most a quarter of the grid wide (the radius bound above),
    // and with many sites about 64 sites' worth of cells, so that a root's
    // candidates from the index stay few.
    const double cells_per_site = double(grid.width) * grid.height / double(sites.size());
    const int rows = std::max(1, row_end - row_begin);
    const int wide = int(std::min(256.0, std::ceil(64.0 * cells_per_site / rows)));
    const int root_columns = std::clamp(std::min(grid.width / 4, wide), 1, 256);
    for (int c0 = 0; c0 < grid.width; c0 += root_columns)
        assigner.root(row_begin, row_end, c0, std::min(grid.width, c0 + root_columns));
}

int nearest_site_brute_force(const std::vector<Eigen::Vector3d>& sites, const Eigen::Vector3d& x) {
    int best = -1;
    double best_d2 = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < sites.size(); ++i) {
        const double d2 = chord2(sites[i], x);
        if (d2 < best_d2) {
            best_d2 = d2;
            best = int(i);
        }
    }
    return best;
}

}  // namespace penumbra::lights
