#include "lights/direction_index.hpp"

#include <algorithm>
#include <cmath>

namespace penumbra::lights {

DirectionIndex::DirectionIndex(const std::vector<Eigen::Vector3d>& directions, int cells)
    : directions_(&directions) {
    // A sphere of area 4π in a cube of side 2: about n² · π/... cells touch it;
    // n ≈ √N / 1.8 gives roughly one direction per occupied cell.
    n_ = cells > 0 ? cells : std::clamp(int(std::sqrt(double(directions.size())) / 1.8), 1, 64);
    size_ = 2.0 / n_;
    const std::size_t total = std::size_t(n_) * n_ * n_;
    std::vector<int> count(total + 1, 0);
    std::vector<std::size_t> cell(directions.size());
    for (std::size_t i = 0; i < directions.size(); ++i) {
        const auto& d = directions[i];
        cell[i] = (std::size_t(cell_of(d.z())) * n_ + cell_of(d.y())) * n_ + cell_of(d.x());
        ++count[cell[i] + 1];
    }
    start_.assign(total + 1, 0);
    for (std::size_t c = 0; c < total; ++c) start_[c + 1] = start_[c] + count[c + 1];
    items_.assign(directions.size(), 0);
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < directions.size(); ++i) items_[fill[cell[i]]++] = int(i);
}

int DirectionIndex::cell_of(double v) const { return std::clamp(int((v + 1.0) / size_), 0, n_ - 1); }

int DirectionIndex::nearest(const Eigen::Vector3d& d) const {
    if (directions_->empty()) return -1;
    const int cx = cell_of(d.x()), cy = cell_of(d.y()), cz = cell_of(d.z());
    int best = -1;
    double best_d2 = 1e300;
    for (int ring = 0; ring <= n_; ++ring) {
        for (int z = std::max(0, cz - ring); z <= std::min(n_ - 1, cz + ring); ++z)
            for (int y = std::max(0, cy - ring); y <= std::min(n_ - 1, cy + ring); ++y)
                for (int x = std::max(0, cx - ring); x <= std::min(n_ - 1, cx + ring); ++x) {
                    if (std::max({std::abs(x - cx), std::abs(y - cy), std::abs(z - cz)}) != ring) continue;
                    const std::size_t c = (std::size_t(z) * n_ + y) * n_ + x;
                    for (int k = start_[c]; k < start_[c + 1]; ++k) {
                        const int i = items_[k];
                        const double d2 = ((*directions_)[i] - d).squaredNorm();
                        if (d2 < best_d2 || (d2 == best_d2 && i < best)) {
                            best_d2 = d2;
                            best = i;
                        }
                    }
                }
        // Unseen directions lie outside the (2·ring+1)³ block of cells around
        // d's cell: at least the distance from d to that block's boundary.
        double safe = 1e300;
        const double p[3] = {d.x(), d.y(), d.z()};
        const int cell[3] = {cx, cy, cz};
        for (int a = 0; a < 3; ++a) {
            const double lo = -1.0 + (cell[a] - ring) * size_, hi = -1.0 + (cell[a] + ring + 1) * size_;
            if (cell[a] - ring > 0) safe = std::min(safe, p[a] - lo);
            if (cell[a] + ring < n_ - 1) safe = std::min(safe, hi - p[a]);
        }
        if (best >= 0 && best_d2 <= safe * safe) break;
    }
    return best;
}

void DirectionIndex::within(const Eigen::Vector3d& d, double angle, std::vector<int>& out) const {
    out.clear();
    const double cos_limit = std::cos(std::min(angle, 3.141592653589793)) - 1e-12;
    const double chord = angle >= 3.141592653589793 ? 2.0 : 2.0 * std::sin(0.5 * angle) + 1e-9;
    const int x0 = cell_of(d.x() - chord), x1 = cell_of(d.x() + chord);
    const int y0 = cell_of(d.y() - chord), y1 = cell_of(d.y() + chord);
    const int z0 = cell_of(d.z() - chord), z1 = cell_of(d.z() + chord);
    for (int z = z0; z <= z1; ++z)
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) {
                const std::size_t c = (std::size_t(z) * n_ + y) * n_ + x;
                for (int k = start_[c]; k < start_[c + 1]; ++k) {
                    const int i = items_[k];
                    if ((*directions_)[i].dot(d) >= cos_limit) out.push_back(i);
                }
            }
    std::sort(out.begin(), out.end());
}

}  // namespace penumbra::lights
