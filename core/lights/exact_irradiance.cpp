#include "lights/exact_irradiance.hpp"

#include <algorithm>
#include <cmath>

#include "common/parallel.hpp"

namespace penumbra::lights {

IrradianceReference::IrradianceReference(const EnvironmentMap& map, int tile) {
    if (tile <= 0) tile = std::clamp(int(std::lround(std::cbrt(double(map.height)))), 1, 16);
    first_.push_back(0);
    for (int r0 = 0; r0 < map.height; r0 += tile)
        for (int c0 = 0; c0 < map.width; c0 += tile) {
            // The tile's lit cells, their flux and moment.
            Eigen::Matrix3d moment = Eigen::Matrix3d::Zero();
            Eigen::Vector3d mean = Eigen::Vector3d::Zero();
            const std::size_t begin = cell_dir_.size();
            for (int r = r0; r < std::min(map.height, r0 + tile); ++r) {
                const double omega = map.solid_angle(r);
                for (int c = c0; c < std::min(map.width, c0 + tile); ++c) {
                    const float* p = map.pixel(r, c);
                    if (p[0] <= 0.0f && p[1] <= 0.0f && p[2] <= 0.0f) continue;
                    const Eigen::Vector3d w = map.direction(r, c);
                    const Eigen::Vector3d f = omega * Eigen::Vector3d(p[0], p[1], p[2]);
                    cell_dir_.push_back(w);
                    cell_flux_.push_back(f);
                    moment += w * f.transpose();
                    mean += w;
                }
            }
            if (cell_dir_.size() == begin) continue;
            // Cone about the cells' mean direction (any axis would do: the
            // test below only needs r to bound every cell's angle from it).
            const Eigen::Vector3d axis = mean.norm() > 1e-12 ? Eigen::Vector3d(mean.normalized())
                                                             : cell_dir_[begin];
            double min_cos = 1.0;
            for (std::size_t i = begin; i < cell_dir_.size(); ++i) min_cos = std::min(min_cos, axis.dot(cell_dir_[i]));
            // sin of the half-angle, padded against rounding; a cone wider
            // than a hemisphere is never wholly on one side (sin r > 1).
            const double sin_r = min_cos > 0.0 ? std::sqrt(std::max(0.0, 1.0 - min_cos * min_cos)) + 1e-9 : 2.0;
            axis_.push_back(axis);
            sin_radius_.push_back(sin_r);
            moment_.push_back(moment);
            first_.push_back(cell_dir_.size());
        }
}

Eigen::Vector3d IrradianceReference::irradiance_at(const Eigen::Vector3d& n) const {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (std::size_t t = 0; t < axis_.size(); ++t) {
        const double s = n.dot(axis_[t]);
        if (s >= sin_radius_[t]) {
            sum += moment_[t].transpose() * n;  // every cell lit: Σ f (n·ω) = n·m
        } else if (s > -sin_radius_[t]) {
            for (std::size_t i = first_[t]; i < first_[t + 1]; ++i) {
                const double c = n.dot(cell_dir_[i]);
                if (c > 0.0) sum += c * cell_flux_[i];
            }
        }
    }
    return sum;
}

Eigen::MatrixXd IrradianceReference::evaluate(const std::vector<Eigen::Vector3d>& normals, int threads) const {
    Eigen::MatrixXd e(Eigen::Index(normals.size()), 3);
    parallel_for(normals.size(), {threads, 8, "lights.exact_irradiance"}, [&](std::size_t b, std::size_t end) {
        for (std::size_t i = b; i < end; ++i) e.row(Eigen::Index(i)) = irradiance_at(normals[i]).transpose();
    });
    return e;
}

}  // namespace penumbra::lights
