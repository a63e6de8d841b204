#include "lights/angular_regions.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Geometry>

#include "common/error.hpp"

namespace penumbra::lights {

Eigen::Vector3d AngularRegionTable::cube_point(int face, double s, double t) const {
    // s, t ∈ [−1, 1] on the face.
    switch (face) {
    case 0: return Eigen::Vector3d(1, s, t).normalized();
    case 1: return Eigen::Vector3d(-1, s, t).normalized();
    case 2: return Eigen::Vector3d(s, 1, t).normalized();
    case 3: return Eigen::Vector3d(s, -1, t).normalized();
    case 4: return Eigen::Vector3d(s, t, 1).normalized();
    default: return Eigen::Vector3d(s, t, -1).normalized();
    }
}

AngularRegionTable::AngularRegionTable(const std::vector<Eigen::Vector3d>& dirs, int g, double lobe) : g_(g) {
    if (g < 1 || g > 256) throw ArgumentError("cells_per_face must be between 1 and 256, got " + std::to_string(g));
    if (!(lobe >= 0.0) || lobe > 3.141592653589793)
        throw ArgumentError("the lobe half-angle must be between 0 and π");
    const int regions = region_count();
    radius_.assign(regions, 0.0);
    std::vector<std::vector<int>> lists(regions);
    for (int r = 0; r < regions; ++r) {
        const int face = r / (g * g), row = (r / g) % g, col = r % g;
        const Eigen::Vector3d p = centre(r);
        double alpha = 0.0;
        // The farthest points of a cell from its centre are its corners;
        // edge midpoints are checked too for safety.
        for (int i = 0; i <= 2; ++i)
            for (int j = 0; j <= 2; ++j) {
                const double s = -1.0 + 2.0 * (col + 0.5 * i) / g, t = -1.0 + 2.0 * (row + 0.5 * j) / g;
                const Eigen::Vector3d q = cube_point(face, s, t);
                alpha = std::max(alpha, std::atan2(q.cross(p).norm(), q.dot(p)));
            }
        radius_[r] = alpha;
        const double cos_beta = std::cos(std::min(3.141592653589793, alpha + lobe)) - 1e-12;
        for (std::size_t k = 0; k < dirs.size(); ++k)
            if (dirs[k].dot(p) >= cos_beta) lists[r].push_back(int(k));
    }
    offsets_.assign(regions + 1, 0);
    for (int r = 0; r < regions; ++r) offsets_[r + 1] = offsets_[r] + int(lists[r].size());
    items_.reserve(offsets_.back());
    for (const auto& l : lists) items_.insert(items_.end(), l.begin(), l.end());
}

int AngularRegionTable::region_of(const Eigen::Vector3d& d) const {
    const double ax = std::abs(d.x()), ay = std::abs(d.y()), az = std::abs(d.z());
    int face;
    double s, t, m;
    if (ax >= ay && ax >= az) { face = d.x() >= 0 ? 0 : 1; m = ax; s = d.y(); t = d.z(); }
    else if (ay >= az) { face = d.y() >= 0 ? 2 : 3; m = ay; s = d.x(); t = d.z(); }
    else { face = d.z() >= 0 ? 4 : 5; m = az; s = d.x(); t = d.y(); }
    if (!(m > 0.0)) return 0;
    const int col = std::clamp(int((s / m + 1.0) * 0.5 * g_), 0, g_ - 1);
    const int row = std::clamp(int((t / m + 1.0) * 0.5 * g_), 0, g_ - 1);
    return (face * g_ + row) * g_ + col;
}

Eigen::Vector3d AngularRegionTable::centre(int r) const {
    const int face = r / (g_ * g_), row = (r / g_) % g_, col = r % g_;
    return cube_point(face, -1.0 + 2.0 * (col + 0.5) / g_, -1.0 + 2.0 * (row + 0.5) / g_);
}

Eigen::MatrixXd irradiance_culled(const AngularRegionTable& table, const std::vector<Light>& lights,
                                  const std::vector<Eigen::Vector3d>& normals, std::size_t* visited) {
    Eigen::MatrixXd e = Eigen::MatrixXd::Zero(Eigen::Index(normals.size()), 3);
    std::size_t visits = 0;
    for (std::size_t i = 0; i < normals.size(); ++i) {
        const int region = table.region_of(normals[i]);
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (const int* k = table.begin(region); k != table.end(region); ++k) {
            const Light& l = lights[*k];
            const double c = normals[i].dot(l.direction);
            if (c > 0.0) sum += c * l.rgb;
        }
        visits += std::size_t(table.end(region) - table.begin(region));
        e.row(Eigen::Index(i)) = sum.transpose();
    }
    if (visited) *visited = visits;
    return e;
}

}  // namespace penumbra::lights
