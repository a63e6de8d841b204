// The spherical Voronoi regions of a set of directions (the lights' samples)
// on a lat-long grid: which direction is nearest to each cell centre. Region
// powers (frame_lights.hpp) sum the map over these regions.
//
// Nearest = the smallest squared chord |s − x|² (the largest dot product)
// as chord2() computes it, ties to the lowest index: the answer of a search
// over every direction (tested against one).
//
// How, so that a cell tests one to three directions instead of all N: the
// grid is cut into blocks of cells. Take a block's centre cell x_B, the
// chord ρ_B within which every cell of the block lies from x_B, and the
// chord d_B from x_B to the nearest candidate s_B. For any cell x of the
// block, its nearest direction s* has |x − s*| ≤ |x − s_B| ≤ ρ_B + d_B, so
//   |x_B − s*| ≤ |x_B − x| + |x − s*| ≤ d_B + 2ρ_B
// (triangle inequality): only the directions within d_B + 2ρ_B of x_B can
// win anywhere in the block. A block left with one candidate is filled
// without testing any cell; a block with several is halved across
// its longer side, each half keeping the candidates that pass its own test,
// until one is left or the block is small enough that its cells test the
// few candidates left one by one.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include <Eigen/Core>

namespace penumbra::lights {

// Sines and cosines of a lat-long grid's cell centres, per row and column
// (latlong.hpp's convention; the column tables go on with zeros for
// detail::kMaxLanes entries past the last column); direction() is
// bit-identical to latlong::pixel_direction and EnvironmentMap::direction
// (tested).
struct LatLongGrid {
    LatLongGrid(int width, int height, double theta_max);
    int width = 0, height = 0;
    std::vector<double> sin_theta, cos_theta;  // per row
    std::vector<double> cos_phi, sin_phi;      // per column
    Eigen::Vector3d direction(int row, int column) const {
        const double s = sin_theta[std::size_t(row)];
        return {s * cos_phi[std::size_t(column)], s * sin_phi[std::size_t(column)], cos_theta[std::size_t(row)]};
    }
};

class DirectionIndex;

// The directions regions are built around, ready for assign_nearest: their
// coordinates side by side and, for many of them, a DirectionIndex. Built
// once per frame, shared by every block of rows.
class Sites {
public:
    explicit Sites(const std::vector<Eigen::Vector3d>& directions);  // not empty
    ~Sites();
    std::size_t size() const { return index_.size(); }

private:
    friend class Assigner;
    std::vector<Eigen::Vector3d> directions_;
    std::vector<int> index_;  // 0, 1, ..., N − 1
    std::vector<double> x_, y_, z_;
    std::unique_ptr<DirectionIndex> search_;  // null when few
};

// Writes the nearest of `sites` to every cell of rows [row_begin, row_end):
// owner[(r − row_begin)·width + c] for cell (r, c).
void assign_nearest(const LatLongGrid& grid, const Sites& sites, int row_begin, int row_end, int* owner);

// |site − x|² as ((Δx² + Δy²) + Δz²): the one arithmetic every nearest-site
// decision uses, so a fast search and a brute-force one agree bit for bit.
double chord2(const Eigen::Vector3d& site, const Eigen::Vector3d& x);

// The nearest of `sites` to `x` by checking every one (the reference the
// tests hold assign_nearest to; −1 when `sites` is empty).
int nearest_site_brute_force(const std::vector<Eigen::Vector3d>& sites, const Eigen::Vector3d& x);

}  // namespace penumbra::lights
