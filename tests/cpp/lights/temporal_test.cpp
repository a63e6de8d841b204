#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "common/error.hpp"
#include "lights/temporal.hpp"

namespace penumbra::lights {
namespace {

constexpr double pi = std::numbers::pi;

TEST(LightsTemporal, paper_filter_is_normalized_symmetric_with_delay_four) {
    const FirFilter f = paper_filter();
    ASSERT_EQ(f.taps.size(), 9u);
    EXPECT_EQ(f.delay(), 4);
    double s = 0;
    for (double t : f.taps) s += t;
    EXPECT_NEAR(s, 1.0, 1e-15);
    for (int i = 0; i < 9; ++i) EXPECT_EQ(f.taps[i], f.taps[8 - i]);
    EXPECT_NEAR(f.taps[4], 0.65223 / 1.09245, 1e-12);
}

TEST(LightsTemporal, remez_design_reproduces_the_papers_equiripple_filter) {
    // The printed taps are an equal-weight equiripple design whose band
    // edges are 5.9 and 8.05 Hz at 21 Hz (not the 7 and 9 Hz the text says).
    const FirFilter mine = design_lowpass(21.0, 5.9, 8.05, 9);
    const FirFilter paper = paper_filter();
    for (int i = 0; i < 9; ++i) EXPECT_NEAR(mine.taps[i], paper.taps[i], 0.002) << "tap " << i;
    // Equiripple: the paper's (unnormalized) response peaks at 1 + δ in the
    // pass band and δ in the stop band with the same δ.
    const double dc = 1.09245;
    double stop = 0.0;
    for (double hz = 8.1; hz <= 10.5; hz += 0.01) stop = std::max(stop, dc * paper.gain(hz, 21.0));
    EXPECT_NEAR(stop, dc - 1.0, 0.005);
}

TEST(LightsTemporal, designed_filters_pass_and_stop_where_asked) {
    for (double rate : {24.0, 30.0, 60.0}) {
        const FirFilter f = filter_for_rate(rate);
        EXPECT_EQ(f.taps.size() % 2, 1u);
        for (double hz = 0; hz <= 5.9; hz += 0.25) EXPECT_NEAR(f.gain(hz, rate), 1.0, 0.2) << rate << " Hz " << hz;
        for (double hz = 8.05; hz <= rate / 2; hz += 0.25) EXPECT_LT(f.gain(hz, rate), 0.12) << rate << " Hz " << hz;
    }
    EXPECT_EQ(filter_for_rate(21.0).taps, paper_filter().taps);
    EXPECT_THROW(design_lowpass(21, 9, 7), ArgumentError);
    EXPECT_THROW(design_lowpass(10, 3, 6), ArgumentError);
}

TEST(LightsTemporal, constants_pass_unchanged_to_the_ends_and_flicker_is_removed) {
    const FirFilter f = paper_filter();
    const std::vector<double> c(30, 3.5);
    for (double v : filter_sequence(c, f)) EXPECT_NEAR(v, 3.5, 1e-12);
    // 9.5 Hz flicker at 21 fps on a constant: mostly gone.
    std::vector<double> x(200);
    for (int t = 0; t < 200; ++t) x[t] = 1.0 + 0.3 * std::sin(2 * pi * 9.5 * t / 21.0);
    const auto y = filter_sequence(x, f);
    double amp = 0;
    for (int t = 20; t < 180; ++t) amp = std::max(amp, std::abs(y[t] - 1.0));
    EXPECT_LT(amp, 0.3 * f.gain(9.5, 21.0) + 1e-3);
    EXPECT_LT(amp, 0.05);
    // Zero delay: a symmetric ramp stays centred on the same frame.
    std::vector<double> ramp(41);
    for (int t = 0; t < 41; ++t) ramp[t] = t;
    EXPECT_NEAR(filter_sequence(ramp, f)[20], 20.0, 1e-12);
}

TEST(LightsTemporal, filtered_lights_keep_power_and_lose_jitter) {
    std::mt19937 rng(6);
    std::normal_distribution<double> jitter(0.0, 0.05);
    std::vector<FrameLights> frames(60);
    for (auto& f : frames) {
        for (int k = 0; k < 3; ++k) {
            Light l;
            l.index = k;
            l.direction = Eigen::Vector3d(k == 0 ? 1 : 0, k == 1 ? 1 : 0, 1 + jitter(rng)).normalized();
            l.rgb = Eigen::Vector3d(1, 1, 1) * (1.0 + 0.2 * jitter(rng));
            l.power = l.rgb.dot(Eigen::Vector3d(0.2126, 0.7152, 0.0722));
            f.lights.push_back(l);
            f.total_power += l.power;
        }
    }
    auto roughness = [](const std::vector<FrameLights>& fr) {
        double s = 0;
        for (std::size_t t = 1; t < fr.size(); ++t) s += (fr[t].lights[0].direction - fr[t - 1].lights[0].direction).norm();
        return s;
    };
    std::vector<double> totals;
    for (auto& f : frames) totals.push_back(f.total_power);
    const auto expected = filter_sequence(totals, paper_filter());
    const double before = roughness(frames);
    std::vector<FrameLights> paper = frames;
    filter_lights(frames, paper_filter());
    filter_lights(paper, paper_filter(), true);
    EXPECT_LT(roughness(frames), 0.6 * before);
    for (std::size_t t = 0; t < frames.size(); ++t) {
        double own = 0, filtered = 0;
        for (const auto& l : frames[t].lights) {
            own += l.power;
            EXPECT_NEAR(l.direction.norm(), 1.0, 1e-12);
        }
        for (const auto& l : paper[t].lights) filtered += l.power;
        // By default each frame keeps its own brightness; the paper's way low-passes it too.
        EXPECT_NEAR(own, totals[t], 1e-9);
        EXPECT_NEAR(frames[t].total_power, totals[t], 1e-9);
        EXPECT_NEAR(filtered, expected[t], 1e-9);
    }
}

TEST(LightsTemporal, a_steadily_turning_light_stays_where_it_is_up_to_the_ends) {
    // One light turning 1° per frame about +z, 20 frames: every centred
    // window is symmetric about the frame, so the filtered direction is the
    // frame's own, the first and last frames included, up to the circle's
    // curvature (the mean of points on a small circle lies a little inside
    // it: up to 3e-4 rad here). A window padded with copies of the end frames
    // would pull them back by a quarter of a frame's motion, 5e-3 rad.
    std::vector<FrameLights> frames(20);
    for (int t = 0; t < 20; ++t) {
        Light l;
        const double a = t * pi / 180.0;
        l.direction = Eigen::Vector3d(std::cos(a), std::sin(a), 0.3).normalized();
        l.rgb = Eigen::Vector3d::Ones();
        l.power = 1.0;
        frames[t].lights = {l};
    }
    const std::vector<FrameLights> raw = frames;
    for (const FirFilter& f : {paper_filter(), filter_for_rate(60.0)}) {
        frames = raw;
        filter_lights(frames, f);
        for (int t = 0; t < 20; ++t)
            EXPECT_LT((frames[t].lights[0].direction - raw[t].lights[0].direction).norm(), 5e-4) << "frame " << t;
    }
}

TEST(LightsTemporal, windows_shrink_symmetrically_at_the_ends) {
    const FirFilter f = paper_filter();
    EXPECT_EQ(f.window(0, 10), std::vector<double>{1.0});
    EXPECT_EQ(f.window(9, 10), std::vector<double>{1.0});
    EXPECT_EQ(f.window(5, 10).size(), 9u);
    for (int t = 0; t < 10; ++t) {
        const auto w = f.window(t, 10);
        double sum = 0;
        for (double v : w) sum += v;
        EXPECT_NEAR(sum, 1.0, 1e-12);
        EXPECT_LE(int(w.size() / 2), std::min(t, 9 - t));
        for (std::size_t i = 0; i < w.size(); ++i) EXPECT_EQ(w[i], w[w.size() - 1 - i]);
    }
}

}  // namespace
}  // namespace penumbra::lights
