#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "lights/exact_irradiance.hpp"
#include "lights/frame_lights.hpp"
#include "lights_test_util.hpp"
#include "sh/point_sets.hpp"

namespace penumbra::lights {
namespace {

using testing::as_map;

// The plain sum over every lit cell, written out here as the definition.
Eigen::MatrixXd every_cell(const EnvironmentMap& map, const std::vector<Eigen::Vector3d>& normals) {
    Eigen::MatrixXd e = Eigen::MatrixXd::Zero(Eigen::Index(normals.size()), 3);
    for (std::size_t i = 0; i < normals.size(); ++i)
        for (int r = 0; r < map.height; ++r)
            for (int c = 0; c < map.width; ++c) {
                const double cosine = normals[i].dot(map.direction(r, c));
                const float* p = map.pixel(r, c);
                if (cosine > 0.0)
                    e.row(Eigen::Index(i)) += cosine * map.solid_angle(r) * Eigen::RowVector3d(p[0], p[1], p[2]);
            }
    return e;
}

// Log-uniform radiance over eight decades, a one-pixel sun and black cells.
Image rough_map(int w, int h, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-4.0, 4.0);
    Image im(w, h, 3);
    for (float& v : im.pixels) v = float(std::pow(10.0, u(rng)));
    for (int c = 0; c < w; c += 3) im.at(c, h / 2, 1) = 0.0f;  // some black cells
    for (int ch = 0; ch < 3; ++ch) im.at(w / 3, std::min(1, h - 1), ch) = 1e7f;  // next to the pole
    return im;
}

TEST(LightsExactIrradiance, tiles_give_the_sum_over_every_cell) {
    // Normals on a Fibonacci set plus the poles and the horizon, where tiles
    // at the map's top and bottom rows straddle the terminator.
    std::vector<Eigen::Vector3d> normals = sh::fibonacci_sphere(200).directions;
    normals.push_back(Eigen::Vector3d::UnitZ());
    normals.push_back(-Eigen::Vector3d::UnitZ());
    normals.push_back(Eigen::Vector3d::UnitX());
    for (auto [w, h, projection] : {std::tuple{96, 48, Projection::equirectangular},
                                    std::tuple{128, 32, Projection::hemisphere_polar},
                                    std::tuple{7, 3, Projection::equirectangular},
                                    std::tuple{1, 1, Projection::equirectangular}}) {
        const EnvironmentMap map = as_map(rough_map(w, h, unsigned(w)), projection);
        const Eigen::MatrixXd want = every_cell(map, normals);
        for (int tile : {0, 1, 4, 16}) {
            const Eigen::MatrixXd got = IrradianceReference(map, tile).evaluate(normals, 2);
            for (Eigen::Index i = 0; i < want.rows(); ++i)
                for (int c = 0; c < 3; ++c)
                    EXPECT_NEAR(got(i, c), want(i, c), 1e-12 * want.row(i).maxCoeff() + 1e-300)
                        << w << "x" << h << " tile " << tile << " normal " << i;
        }
    }
}

TEST(LightsExactIrradiance, skips_black_cells_and_a_black_map_is_black) {
    const EnvironmentMap black = as_map(testing::constant_image(64, 32, 0, 0, 0));
    const IrradianceReference ref(black);
    EXPECT_EQ(ref.cell_count(), 0u);
    EXPECT_EQ(ref.evaluate(sh::fibonacci_sphere(10).directions).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace penumbra::lights
