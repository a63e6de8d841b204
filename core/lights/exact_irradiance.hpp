// The map's own irradiance E(n) = Σ_cells L Ω max(0, n·ω) (every cell a
// point at its centre), the reference every rig is measured and fitted
// against, computed exactly but without visiting every cell for every normal.
//
// The lit cells are grouped into tiles of a few rows × columns. A tile keeps
// its flux-weighted moment per channel, m_c = Σ f_c ω, and a bounding cone
// (axis a, half-angle r ≥ the angle of each of its cells from a). For a tile
// wholly on the lit side of a normal (n·a ≥ sin r, so n·ω ≥ 0 for every
// cell) the clamp is the identity and Σ f_c max(0, n·ω) = n·m_c exactly; a
// tile wholly behind (n·a ≤ −sin r) adds nothing; only the tiles the
// terminator crosses are summed cell by cell. With b × b tiles on a W × H
// map a normal costs W·H/b² tile tests plus about 2·(W/b)·b² cells, against
// W·H for the plain sum: at 1024 × 512, b = 8, about 20× fewer terms. The
// result equals the plain sum up to the order of the additions.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "lights/environment.hpp"

namespace penumbra::lights {

class IrradianceReference {
public:
    // tile = rows and columns per tile; 0 picks about ∛(height) (8 at 512 rows).
    explicit IrradianceReference(const EnvironmentMap& map, int tile = 0);

    // RGB irradiance, one row per normal; parallel over normals.
    Eigen::MatrixXd evaluate(const std::vector<Eigen::Vector3d>& normals, int threads = 0) const;

    std::size_t tile_count() const { return axis_.size(); }
    std::size_t cell_count() const { return cell_dir_.size(); }

private:
    Eigen::Vector3d irradiance_at(const Eigen::Vector3d& n) const;
    // Tiles: cone axis and sin of its half-angle, moment per channel (3 × 3,
    // column c = Σ f_c ω), and their cells' range in cell_dir_/cell_flux_.
    std::vector<Eigen::Vector3d> axis_;
    std::vector<double> sin_radius_;
    std::vector<Eigen::Matrix3d> moment_;
    std::vector<std::size_t> first_;  // tile t's cells: [first_[t], first_[t + 1])
    std::vector<Eigen::Vector3d> cell_dir_, cell_flux_;
};

}  // namespace penumbra::lights
