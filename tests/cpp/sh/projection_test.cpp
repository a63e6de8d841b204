// Projection of samples, lights and equirectangular images. The image tests pin Blender's orientation: spots placed
// at the landmarks Cycles' direction_to_equirectangular gives (centre = +x,
// quarter from the left = +y, top = +z) must land on the right band-1
// coefficient with the right sign.
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "common/error.hpp"
#include "common/progress.hpp"
#include "sh/basis.hpp"
#include "sh/point_sets.hpp"
#include "sh/projection.hpp"
#include "sh_test_util.hpp"

namespace penumbra::sh {
namespace {

constexpr double pi = std::numbers::pi;

struct Image {
    int height, width, channels;
    std::vector<float> pixels;
    Image(int h, int w, int c = 3, float fill = 0.0f)
        : height(h), width(w), channels(c), pixels(std::size_t(h) * w * c, fill) {}
    float* at(int row, int column) { return &pixels[(std::size_t(row) * width + column) * channels]; }
    void set(int row, int column, float value) {
        for (int ch = 0; ch < 3; ++ch) at(row, column)[ch] = value;
    }
    EnvironmentProjection project(int order, const Progress& progress = {}) const {
        return project_equirectangular(order, pixels.data(), height, width, channels, progress);
    }
};

TEST(Projection, fibonacci_projection_recovers_a_basis_function) {
    constexpr int order = 4;
    const PointSet set = fibonacci_sphere(20000);
    Eigen::MatrixXd values(set.directions.size(), 1);
    for (std::size_t i = 0; i < set.directions.size(); ++i)
        values(Eigen::Index(i), 0) = testing::reference_y(2, 1, set.directions[i]);
    const Eigen::MatrixXd c = project_samples(order, set, values);
    for (int i = 0; i < coefficient_count(order); ++i) EXPECT_NEAR(c(i, 0), i == sh_index(2, 1) ? 1.0 : 0.0, 1e-3);
}

TEST(Projection, samples_with_exact_weights_project_a_band_limited_function_exactly) {
    constexpr int order = 6;
    std::mt19937_64 rng(4);
    std::normal_distribution<double> normal;
    Eigen::VectorXd c(coefficient_count(order));
    for (auto& v : c) v = normal(rng);
    const PointSet q = exact_sphere_quadrature(2 * order - 2);
    Eigen::MatrixXd values(q.directions.size(), 1);
    for (std::size_t k = 0; k < q.directions.size(); ++k) {
        double f = 0.0;
        for (int l = 0; l < order; ++l)
            for (int m = -l; m <= l; ++m) f += c[sh_index(l, m)] * testing::reference_y(l, m, q.directions[k]);
        values(Eigen::Index(k), 0) = f;
    }
    EXPECT_LT((project_samples(order, q, values).col(0) - c).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_THROW(project_samples(order, q.directions, Eigen::MatrixXd::Zero(3, 1)), ArgumentError);
}

TEST(Projection, delta_light_projects_to_irradiance_times_basis) {
    constexpr int order = 5;
    const Eigen::Vector3d up = Eigen::Vector3d::UnitZ(), d = Eigen::Vector3d(0.2, -0.5, 0.4);
    Eigen::MatrixXd rgb(2, 3);
    rgb << 1.0, 2.0, 3.0, 0.5, 0.0, 4.0;
    const Eigen::MatrixXd c = project_lights(order, {up, d}, rgb);
    const Eigen::Vector3d dn = d.normalized();
    for (int l = 0; l < order; ++l)
        for (int m = -l; m <= l; ++m) {
            // From +z only y_l0 = sqrt((2l+1)/4π) survives.
            const double from_up = (m == 0) ? std::sqrt((2.0 * l + 1.0) / (4.0 * pi)) : 0.0;
            const double from_d = testing::reference_y(l, m, dn);
            for (int ch = 0; ch < 3; ++ch)
                EXPECT_NEAR(c(sh_index(l, m), ch), rgb(0, ch) * from_up + rgb(1, ch) * from_d, 1e-13);
        }
}

TEST(Projection, pixel_solid_angles_sum_to_4pi) {
    const int h = 7, w = 9;
    double total = 0.0;
    for (int r = 0; r < h; ++r) total += w * equirectangular_solid_angle(r, h, w);
    EXPECT_NEAR(total, 4.0 * pi, 1e-13);
}

TEST(Projection, constant_image_projects_to_sqrt_4pi_times_radiance_exactly) {
    for (int order : {8, max_order})
    for (auto [h, w] : {std::pair{1, 1}, std::pair{2, 3}, std::pair{3, 1}, std::pair{17, 40}, std::pair{64, 128}}) {
        Image image(h, w);
        for (int r = 0; r < h; ++r)
            for (int c = 0; c < w; ++c) {
                image.at(r, c)[0] = 0.5f;
                image.at(r, c)[1] = 1.0f;
                image.at(r, c)[2] = 2.0f;
            }
        const EnvironmentProjection p = image.project(order);
        const double expected[3] = {0.5, 1.0, 2.0};
        for (int ch = 0; ch < 3; ++ch) {
            EXPECT_NEAR(p.coefficients(0, ch), std::sqrt(4.0 * pi) * expected[ch], 1e-12) << h << "x" << w;
            for (int i = 1; i < coefficient_count(order); ++i) EXPECT_NEAR(p.coefficients(i, ch), 0.0, 1e-12);
        }
        EXPECT_EQ(p.non_finite_pixels, 0u);
    }
}

// Band-1 coefficients (y, z, x) of the red channel.
Eigen::Vector3d band_1(const EnvironmentProjection& p) {
    return {p.coefficients(sh_index(1, -1), 0), p.coefficients(sh_index(1, 0), 0), p.coefficients(sh_index(1, 1), 0)};
}

TEST(Projection, image_centre_faces_plus_x) {
    Image image(64, 128);
    for (int r : {31, 32})
        for (int c : {63, 64}) image.set(r, c, 1.0f);
    const Eigen::Vector3d yzx = band_1(image.project(2));
    EXPECT_GT(yzx[2], 0.0);
    EXPECT_NEAR(yzx[0], 0.0, 1e-12 * yzx[2]);
    EXPECT_NEAR(yzx[1], 0.0, 1e-12 * yzx[2]);
}

TEST(Projection, image_left_and_right_edges_face_minus_x) {
    Image image(64, 128);
    for (int r : {31, 32})
        for (int c : {0, 127}) image.set(r, c, 1.0f);
    const Eigen::Vector3d yzx = band_1(image.project(2));
    EXPECT_LT(yzx[2], 0.0);
    EXPECT_NEAR(yzx[0], 0.0, 1e-12 * std::abs(yzx[2]));
}

TEST(Projection, quarter_from_the_left_faces_plus_y_and_three_quarters_minus_y) {
    Image left(64, 128), right(64, 128);
    for (int r : {31, 32})
        for (int c : {31, 32}) left.set(r, c, 1.0f);
    for (int r : {31, 32})
        for (int c : {95, 96}) right.set(r, c, 1.0f);
    const Eigen::Vector3d a = band_1(left.project(2)), b = band_1(right.project(2));
    EXPECT_GT(a[0], 0.0);
    EXPECT_NEAR(a[2], 0.0, 1e-12 * a[0]);
    EXPECT_LT(b[0], 0.0);
    EXPECT_NEAR(b[2], 0.0, 1e-12 * std::abs(b[0]));
}

TEST(Projection, top_row_of_the_file_is_up) {
    Image image(64, 128);
    for (int c = 0; c < 128; ++c) image.set(0, c, 1.0f);
    const Eigen::Vector3d yzx = band_1(image.project(2));
    EXPECT_GT(yzx[1], 0.0);
    EXPECT_NEAR(yzx[0], 0.0, 1e-12 * yzx[1]);
    EXPECT_NEAR(yzx[2], 0.0, 1e-12 * yzx[1]);
}

TEST(Projection, images_of_x_y_z_land_on_the_matching_band_1_coefficient) {
    // Radiance = one Cartesian component of the pixel-centre direction,
    // computed here from the mapping in projection.hpp.
    const int h = 96, w = 192;
    const double k = std::sqrt(4.0 * pi / 3.0);  // ∫ x·y_11 dω
    for (int axis = 0; axis < 3; ++axis) {
        Image image(h, w);
        for (int r = 0; r < h; ++r)
            for (int c = 0; c < w; ++c) {
                const double theta = pi * (r + 0.5) / h, phi = pi - 2.0 * pi * (c + 0.5) / w;
                const double d[3] = {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
                image.set(r, c, float(d[axis]));
            }
        const EnvironmentProjection p = image.project(4);
        const int expected_index = (axis == 0) ? sh_index(1, 1) : (axis == 1) ? sh_index(1, -1) : sh_index(1, 0);
        for (int i = 0; i < 16; ++i)
            EXPECT_NEAR(p.coefficients(i, 0), i == expected_index ? k : 0.0, 1e-3) << "axis " << axis << " index " << i;
    }
}

TEST(Projection, image_of_a_band_limited_function_converges_to_its_coefficients) {
    constexpr int order = 5;
    std::mt19937_64 rng(31);
    std::normal_distribution<double> normal;
    Eigen::VectorXd c(coefficient_count(order));
    for (auto& v : c) v = normal(rng);
    double previous_error = 1e9;
    for (int h : {32, 64, 128}) {
        Image image(h, 2 * h);
        for (int r = 0; r < h; ++r)
            for (int col = 0; col < 2 * h; ++col) {
                const Eigen::Vector3d d = equirectangular_direction(r, col, h, 2 * h);
                double f = 0.0;
                for (int l = 0; l < order; ++l)
                    for (int m = -l; m <= l; ++m) f += c[sh_index(l, m)] * testing::reference_y(l, m, d);
                image.set(r, col, float(f));
            }
        const double error = (image.project(order).coefficients.col(0) - c).cwiseAbs().maxCoeff();
        EXPECT_LT(error, previous_error / 3.0) << h;  // box pixels: O(h^-2)
        previous_error = error;
    }
    EXPECT_LT(previous_error, 5e-3);
}

TEST(Projection, non_finite_pixels_count_as_zero_and_are_reported) {
    Image with_bad(16, 32, 4, 2.0f), with_zero(16, 32, 4, 2.0f);
    with_bad.at(3, 5)[1] = std::numeric_limits<float>::quiet_NaN();
    with_bad.at(10, 20)[0] = std::numeric_limits<float>::infinity();
    with_bad.at(10, 20)[3] = std::numeric_limits<float>::quiet_NaN();  // alpha: ignored
    with_bad.at(7, 7)[2] = -1.0f;
    with_zero.at(3, 5)[1] = 0.0f;
    with_zero.at(10, 20)[0] = 0.0f;
    with_zero.at(7, 7)[2] = -1.0f;
    const EnvironmentProjection bad = with_bad.project(3), zero = with_zero.project(3);
    EXPECT_EQ(bad.non_finite_pixels, 2u);
    EXPECT_EQ(bad.negative_pixels, 1u);
    EXPECT_LT((bad.coefficients - zero.coefficients).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_TRUE(bad.coefficients.allFinite());
}

TEST(Projection, reports_progress_by_row_batches_and_can_be_cancelled) {
    Image image(100, 8, 3, 1.0f);
    std::vector<double> fractions;
    image.project(2, Progress([&](double f) { fractions.push_back(f); return true; }));
    ASSERT_EQ(fractions.size(), 4u);  // after rows 32, 64, 96, 100
    EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
    for (std::size_t i = 1; i < fractions.size(); ++i) EXPECT_GT(fractions[i], fractions[i - 1]);
    EXPECT_THROW(image.project(2, Progress([](double) { return false; })), Cancelled);
}

TEST(Projection, bad_image_arguments_throw) {
    std::vector<float> px(12, 1.0f);
    EXPECT_THROW(project_equirectangular(2, px.data(), 0, 4, 3), ArgumentError);
    EXPECT_THROW(project_equirectangular(2, px.data(), 2, 2, 2), ArgumentError);
    EXPECT_THROW(project_equirectangular(0, px.data(), 2, 2, 3), ArgumentError);
}

}  // namespace
}  // namespace penumbra::sh
