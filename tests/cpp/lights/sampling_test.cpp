#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "common/error.hpp"
#include "lights/sampling.hpp"
#include "lights_test_util.hpp"

namespace penumbra::lights {
namespace {

constexpr double pi = std::numbers::pi;

EnvironmentMap random_positive_map(int w, int h, bool full, unsigned seed) {
    std::mt19937 rng(seed);
    std::lognormal_distribution<float> lum(0.0f, 1.5f);
    Image im(w, h, 3);
    for (float& v : im.pixels) v = lum(rng);
    return testing::as_map(im, full ? Projection::equirectangular : Projection::hemisphere_polar);
}

TEST(LightsSampling, halton_points_are_progressive) {
    const auto a = sample_points(10, false), b = sample_points(100, false);
    EXPECT_DOUBLE_EQ(a[0].x(), 0.5);
    EXPECT_DOUBLE_EQ(a[0].y(), 1.0 / 3);
    EXPECT_DOUBLE_EQ(a[2].x(), 0.75);
    EXPECT_DOUBLE_EQ(a[2].y(), 1.0 / 9);
    for (int i = 0; i < 10; ++i) EXPECT_EQ(a[i], b[i]);
    const auto c = sample_points(10, true), d = sample_points(5000, true);
    for (int i = 0; i < 10; ++i) EXPECT_EQ(c[i], d[i]);
}

double min_torus_distance(const std::vector<Eigen::Vector2d>& p) {
    double best = 1.0;
    for (std::size_t i = 0; i < p.size(); ++i)
        for (std::size_t j = i + 1; j < p.size(); ++j) {
            double dx = p[i].x() - p[j].x(), dy = p[i].y() - p[j].y();
            dx -= std::round(dx);
            dy -= std::round(dy);
            best = std::min(best, std::hypot(dx, dy));
        }
    return best;
}

TEST(LightsSampling, lloyd_relaxation_spreads_the_points_deterministically) {
    const auto halton = sample_points(4096, false);
    const auto relaxed = sample_points(4096, true);
    EXPECT_EQ(relaxed, sample_points(4096, true));
    EXPECT_GT(min_torus_distance(relaxed), 1.3 * min_torus_distance(halton));
    for (const auto& p : relaxed) {
        EXPECT_GE(p.x(), 0.0); EXPECT_LT(p.x(), 1.0); EXPECT_GE(p.y(), 0.0); EXPECT_LT(p.y(), 1.0);
    }
}

TEST(LightsSampling, concentric_map_round_trips) {
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int i = 0; i < 2000; ++i) {
        const double a = u(rng), b = u(rng);
        const Eigen::Vector2d disc = concentric_square_to_disc(a, b);
        EXPECT_LE(disc.norm(), 1.0 + 1e-12);
        const Eigen::Vector2d back = concentric_disc_to_square(disc);
        EXPECT_NEAR(back.x(), a, 1e-12);
        EXPECT_NEAR(back.y(), b, 1e-12);
    }
}

TEST(LightsSampling, both_transforms_are_invertible_where_the_pdf_is_positive) {
    std::mt19937 rng(4);
    std::uniform_real_distribution<double> u(0.001, 0.999);
    for (bool full : {true, false}) {
        const EnvironmentMap map = random_positive_map(64, 32, full, 7);
        const auto dist = luminance_distribution(map);
        for (auto kind : {SamplerKind::havran, SamplerKind::standard}) {
            const auto s = make_sampler(kind, dist);
            for (int i = 0; i < 2000; ++i) {
                const double a = u(rng), b = u(rng);
                const Eigen::Vector2d back = s->invert(s->sample(a, b).direction);
                EXPECT_NEAR(back.x(), a, 1e-8) << int(kind) << " full " << full;
                EXPECT_NEAR(back.y(), b, 1e-8) << int(kind) << " full " << full;
            }
        }
    }
}

TEST(LightsSampling, havran_transform_is_continuous_and_standard_is_not) {
    // Along random segments of the unit square, the largest angle between
    // consecutive samples must shrink with the step for a continuous map
    // and stay large for one with jumps.
    const EnvironmentMap map = random_positive_map(64, 32, false, 9);
    const auto dist = luminance_distribution(map);
    auto largest_jump = [&](SamplerKind kind, int steps) {
        const auto s = make_sampler(kind, dist);
        std::mt19937 rng(10);
        std::uniform_real_distribution<double> u(0.0, 1.0);
        double worst = 0.0;
        for (int segment = 0; segment < 60; ++segment) {
            const Eigen::Vector2d a(u(rng), u(rng)), b(u(rng), u(rng));
            Eigen::Vector3d previous = s->sample(a.x(), a.y()).direction;
            for (int i = 1; i <= steps; ++i) {
                const Eigen::Vector2d p = a + (b - a) * double(i) / steps;
                const Eigen::Vector3d d = s->sample(p.x(), p.y()).direction;
                worst = std::max(worst, std::acos(std::clamp(d.dot(previous), -1.0, 1.0)));
                previous = d;
            }
        }
        return worst;
    };
    const double havran_coarse = largest_jump(SamplerKind::havran, 512);
    const double havran_fine = largest_jump(SamplerKind::havran, 8192);
    EXPECT_LT(havran_fine, havran_coarse / 4);
    EXPECT_GT(largest_jump(SamplerKind::standard, 8192), 0.3);  // row changes and the φ = ±π seam
}

// Histogram of 2^14 Halton samples over 8x4 blocks of a 64x32 map against the
// blocks' share of Y·Ω; returns the largest relative error and the total
// variation distance.
std::pair<double, double> block_histogram_error(const Image& im, SamplerKind kind) {
    const EnvironmentMap map = testing::as_map(im);
    const auto dist = luminance_distribution(map);
    const int n = 1 << 14;
    const auto s = make_sampler(kind, dist);
    std::vector<double> hist(32, 0.0), expected(32, 0.0);
    for (const auto& p : sample_points(n, false)) {
        const Sample smp = s->sample(p.x(), p.y());
        hist[(smp.row / 8) * 8 + smp.column / 8] += 1.0 / n;
    }
    for (int r = 0; r < 32; ++r)
        for (int c = 0; c < 64; ++c) expected[(r / 8) * 8 + c / 8] += dist.weight[r * 64 + c] / dist.total;
    double worst = 0.0, tv = 0.0;
    for (int k = 0; k < 32; ++k) {
        worst = std::max(worst, std::abs(hist[k] - expected[k]) / std::max(expected[k], 0.02));
        tv += 0.5 * std::abs(hist[k] - expected[k]);
    }
    return {worst, tv};
}

Image block_map(bool separable) {
    Image im(64, 32, 3);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> block(0.1f, 10.0f);
    std::vector<float> rows(4), cols(8), b(32);
    for (float& v : rows) v = block(rng);
    for (float& v : cols) v = block(rng);
    for (float& v : b) v = block(rng);
    for (int r = 0; r < 32; ++r)
        for (int c = 0; c < 64; ++c)
            for (int ch = 0; ch < 3; ++ch)
                im.at(c, r, ch) = separable ? rows[r / 8] * cols[c / 8] : b[(r / 8) * 8 + c / 8];
    return im;
}

TEST(LightsSampling, samples_follow_the_luminance_pdf) {
    // Separable map: every row's conditional CDF has the same shape, so
    // Havran's interpolation between rows is exact and both must match.
    for (auto kind : {SamplerKind::havran, SamplerKind::standard})
        EXPECT_LT(block_histogram_error(block_map(true), kind).first, 0.02) << int(kind);
    // General map: the standard inversion is exact; Havran's interpolated
    // conditionals move mass by up to one row across block edges (the price
    // of continuity), bounded here in total variation.
    EXPECT_LT(block_histogram_error(block_map(false), SamplerKind::standard).first, 0.02);
    EXPECT_LT(block_histogram_error(block_map(false), SamplerKind::havran).second, 0.08);
}

TEST(LightsSampling, a_black_map_samples_finite_directions) {
    const EnvironmentMap map = testing::as_map(testing::constant_image(16, 8, 0, 0, 0));
    const auto dist = luminance_distribution(map);
    EXPECT_EQ(dist.total, 0.0);
    for (auto kind : {SamplerKind::havran, SamplerKind::standard}) {
        const auto s = make_sampler(kind, dist);
        for (const auto& p : sample_points(64, false)) EXPECT_TRUE(s->sample(p.x(), p.y()).direction.allFinite());
    }
}

}  // namespace
}  // namespace penumbra::lights
