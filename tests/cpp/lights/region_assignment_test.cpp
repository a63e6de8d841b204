// Region powers' assignment of map cells to their nearest sample
// (lights/region_assignment.hpp) and the sums over it (frame_lights.hpp, region
// mode), held to a brute-force search over every sample: the same nearest
// sample for every cell (ties to the lowest index) on every SIMD target, and
// the same powers, centroids and spreads, on random and extreme maps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "common/latlong.hpp"
#include "common/simd_target.hpp"
#include "lights/frame_lights.hpp"
#include "lights/region_assignment.hpp"
#include "lights_test_util.hpp"

namespace penumbra::lights {
namespace {

using testing::as_map;

std::vector<Eigen::Vector3d> random_directions(int n, unsigned seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> g(0.0, 1.0);
    std::vector<Eigen::Vector3d> d(static_cast<std::size_t>(n), Eigen::Vector3d::Zero());
    for (auto& v : d) v = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    return d;
}

// n directions within `radius` radians of `centre`.
std::vector<Eigen::Vector3d> clustered_directions(int n, const Eigen::Vector3d& centre, double radius, unsigned seed) {
    std::vector<Eigen::Vector3d> d = random_directions(n, seed);
    const Eigen::Vector3d c = centre.normalized();
    for (auto& v : d) v = (c + std::tan(radius) * (v - v.dot(c) * c)).normalized();
    return d;
}

struct Grid {
    int width, height;
    bool full_sphere;
};

double theta_max(const Grid& g) { return g.full_sphere ? latlong::full_sphere : latlong::upper_hemisphere; }

// Every cell's nearest site by the brute-force search.
std::vector<int> brute_force_owners(const Grid& g, const std::vector<Eigen::Vector3d>& sites) {
    const LatLongGrid grid(g.width, g.height, theta_max(g));
    std::vector<int> owner;
    for (int r = 0; r < g.height; ++r)
        for (int c = 0; c < g.width; ++c) owner.push_back(nearest_site_brute_force(sites, grid.direction(r, c)));
    return owner;
}

// Cells whose assignment, done in bands of `band_rows`, differs from `expected`.
int mismatches(const Grid& g, const std::vector<Eigen::Vector3d>& sites, int band_rows, const std::vector<int>& expected) {
    const LatLongGrid grid(g.width, g.height, theta_max(g));
    const Sites prepared(sites);
    std::vector<int> owner(std::size_t(g.width) * g.height, -2);
    for (int r = 0; r < g.height; r += band_rows)
        assign_nearest(grid, prepared, r, std::min(g.height, r + band_rows), owner.data() + std::size_t(r) * g.width);
    int wrong = 0;
    for (std::size_t i = 0; i < owner.size(); ++i) wrong += owner[i] != expected[i];
    return wrong;
}

TEST(LightsRegionAssignment, grid_directions_are_bit_identical_to_the_maps) {
    for (const Grid g : {Grid{360, 90, false}, Grid{1024, 512, true}, Grid{7, 3, true}, Grid{1, 1, true}}) {
        Image im = testing::constant_image(g.width, g.height, 1, 1, 1);
        const EnvironmentMap map = as_map(im, g.full_sphere ? Projection::equirectangular : Projection::hemisphere_polar);
        const LatLongGrid grid(g.width, g.height, map.theta_max());
        for (int r = 0; r < g.height; ++r)
            for (int c = 0; c < g.width; ++c) {
                const Eigen::Vector3d a = grid.direction(r, c), b = map.direction(r, c);
                ASSERT_TRUE(a.x() == b.x() && a.y() == b.y() && a.z() == b.z()) << g.width << "x" << g.height << " " << r << "," << c;
            }
    }
}

TEST(LightsRegionAssignment, every_cell_gets_the_brute_force_nearest_sample_on_every_simd_target) {
    struct Case {
        Grid grid;
        std::vector<Eigen::Vector3d> sites;
        const char* what;
    };
    std::vector<Case> cases;
    cases.push_back({{256, 128, true}, random_directions(300, 1), "300 random"});
    cases.push_back({{360, 90, false}, random_directions(300, 2), "300 random, hemisphere grid"});
    cases.push_back({{97, 45, true}, random_directions(1, 3), "N = 1"});
    cases.push_back({{97, 45, true}, random_directions(2, 4), "N = 2"});
    cases.push_back({{128, 64, true}, clustered_directions(200, {0.3, -0.2, 0.9}, 0.01, 5),
                     "200 within 0.6° (far cells: every candidate nearly as far)"});
    // Ties: each direction three times; the lowest index must win.
    std::vector<Eigen::Vector3d> repeated;
    for (const auto& d : random_directions(40, 6))
        for (int k = 0; k < 3; ++k) repeated.push_back(d);
    cases.push_back({{128, 64, true}, repeated, "every direction three times"});
    // N = cells, each site exactly at a cell centre (and in scrambled order):
    // the brute force and the index-backed search (N > 2048) alike.
    for (const Grid g : {Grid{48, 24, true}, Grid{80, 40, true}}) {
        const LatLongGrid grid(g.width, g.height, latlong::full_sphere);
        std::vector<Eigen::Vector3d> centres;
        for (int r = 0; r < g.height; ++r)
            for (int c = 0; c < g.width; ++c) centres.push_back(grid.direction(r, c));
        std::shuffle(centres.begin(), centres.end(), std::mt19937(7));
        cases.push_back({g, centres, "N = cells, at the cell centres"});
    }
    cases.push_back({{96, 48, true}, random_directions(3000, 8), "3000 random (index-backed)"});

    const std::vector<std::string> targets = simd_targets();
    ASSERT_FALSE(targets.empty());
    for (const Case& c : cases) {
        const std::vector<int> expected = brute_force_owners(c.grid, c.sites);
        for (const std::string& target : targets) {
            force_simd_target(target);
            for (const int band : {16, 5})
                EXPECT_EQ(mismatches(c.grid, c.sites, band, expected), 0)
                    << c.what << ", " << target << ", bands of " << band;
        }
    }
    force_simd_target("");
}

// The region sums done the slow way: every lit cell to its brute-force
// nearest sample, Σ L Ω, Σ Y Ω ω, Σ Y Ω; spread by atan2.
struct Reference {
    std::vector<Eigen::Vector3d> rgb, moment;
    std::vector<double> y, spread;
};

Reference reference_regions(const EnvironmentMap& map, const std::vector<Eigen::Vector3d>& sites,
                            const std::array<double, 3>& luminance) {
    const std::size_t n = sites.size();
    Reference ref{std::vector<Eigen::Vector3d>(n, Eigen::Vector3d::Zero()),
                  std::vector<Eigen::Vector3d>(n, Eigen::Vector3d::Zero()), std::vector<double>(n, 0.0),
                  std::vector<double>(n, 0.0)};
    std::vector<int> owner(std::size_t(map.width) * map.height, -1);
    for (int r = 0; r < map.height; ++r)
        for (int c = 0; c < map.width; ++c) {
            const float* p = map.pixel(r, c);
            if (p[0] <= 0.0f && p[1] <= 0.0f && p[2] <= 0.0f) continue;
            const Eigen::Vector3d w = map.direction(r, c);
            const int k = nearest_site_brute_force(sites, w);
            owner[std::size_t(r) * map.width + c] = k;
            const double y = std::max(0.0, luminance[0] * p[0] + luminance[1] * p[1] + luminance[2] * p[2]) *
                             map.solid_angle(r);
            ref.rgb[std::size_t(k)] += map.solid_angle(r) * Eigen::Vector3d(p[0], p[1], p[2]);
            ref.moment[std::size_t(k)] += y * w;
            ref.y[std::size_t(k)] += y;
        }
    std::vector<double> second(n, 0.0);
    for (int r = 0; r < map.height; ++r)
        for (int c = 0; c < map.width; ++c) {
            const int k = owner[std::size_t(r) * map.width + c];
            if (k < 0) continue;
            const float* p = map.pixel(r, c);
            const double y = std::max(0.0, luminance[0] * p[0] + luminance[1] * p[1] + luminance[2] * p[2]) *
                             map.solid_angle(r);
            const double m = ref.moment[std::size_t(k)].norm();
            const Eigen::Vector3d l = m > 1e-300 ? Eigen::Vector3d(ref.moment[std::size_t(k)] / m) : sites[std::size_t(k)];
            const Eigen::Vector3d w = map.direction(r, c);
            const double a = std::atan2(w.cross(l).norm(), w.dot(l));
            second[std::size_t(k)] += y * a * a;
        }
    for (std::size_t k = 0; k < n; ++k) ref.spread[k] = ref.y[k] > 0.0 ? std::sqrt(second[k] / ref.y[k]) : 0.0;
    return ref;
}

void expect_matches_reference(const EnvironmentMap& map, int count, const std::string& what) {
    for (const int threads : {1, 3}) {
        LightOptions o;
        o.count = count;
        o.threads = threads;
        o.fit_irradiance = false;  // the regions' own sums, before any fit moves them
        const FrameLights f = compute_lights(map, o);
        std::vector<Eigen::Vector3d> sites;
        for (const Light& l : f.lights) sites.push_back(l.sample_direction);
        const Reference ref = reference_regions(map, sites, o.luminance);
        double scale = 0.0;
        for (const auto& v : ref.rgb) scale = std::max(scale, v.cwiseAbs().maxCoeff());
        for (std::size_t k = 0; k < sites.size(); ++k) {
            const Light& l = f.lights[k];
            SCOPED_TRACE(what + ", light " + std::to_string(k) + ", " + std::to_string(threads) + " threads");
            for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(l.rgb[ch], ref.rgb[k][ch], 1e-12 * scale + 1e-300);
            const double m = ref.moment[k].norm();
            if (m > 1e-300 && ref.y[k] > 0.0) {
                EXPECT_LT((l.direction - ref.moment[k] / m).norm(), 1e-12);
                EXPECT_NEAR(l.spread, ref.spread[k], 1e-9 * ref.spread[k] + 1e-12);
            } else {  // no lit cell of positive luminance: the light stays at its sample
                EXPECT_EQ(l.direction, l.sample_direction);
                EXPECT_EQ(l.spread, 0.0);
            }
        }
    }
}

TEST(LightsRegionAssignment, region_sums_match_a_brute_force_reference_on_random_and_extreme_maps) {
    std::mt19937 rng(11);
    std::lognormal_distribution<float> radiance(0.0f, 2.0f);
    // A random map spanning many orders of magnitude, with black patches.
    Image noisy(96, 48, 3);
    for (std::size_t i = 0; i < noisy.pixel_count(); ++i) {
        const bool black = (i / 7) % 5 == 0;
        for (int ch = 0; ch < 3; ++ch) noisy.pixels[3 * i + std::size_t(ch)] = black ? 0.0f : radiance(rng);
    }
    expect_matches_reference(as_map(noisy), 37, "random map");
    expect_matches_reference(as_map(noisy, Projection::hemisphere_polar), 64, "random hemisphere map");
    expect_matches_reference(as_map(noisy), 1, "N = 1");
    expect_matches_reference(as_map(noisy), 96 * 48, "N = cells");
    expect_matches_reference(as_map(testing::constant_image(40, 20, 0, 0, 0)), 16, "all-black map");
    Image one = testing::constant_image(40, 20, 0, 0, 0);
    one.at(13, 4, 1) = 1e6f;
    expect_matches_reference(as_map(one), 16, "one bright pixel");
    expect_matches_reference(as_map(one), 40 * 20, "one bright pixel, N = cells");
    expect_matches_reference(as_map(testing::sky_and_sun(256, 128, 0.5, Eigen::Vector3d(0.3, -0.5, 0.6), 0.05, 2e4)),
                             300, "sky and sun");
}

TEST(LightsRegionAssignment, a_map_with_negative_values_keeps_its_lit_cells_whole_and_drops_black_ones) {
    // Not what make_environment produces (it zeroes negatives), but a map
    // built by hand: a cell counts when some channel is positive, and then
    // with all its channels, as before.
    EnvironmentMap map = as_map(testing::constant_image(64, 32, 1.0f, 2.0f, 0.5f));
    for (std::size_t i = 0; i < map.rgb.size(); i += 7) map.rgb[i] = -3.0f;                 // lit, one channel negative
    for (std::size_t p = 5; p < map.rgb.size() / 3; p += 11) map.rgb[3 * p] = map.rgb[3 * p + 1] = map.rgb[3 * p + 2] = -1.0f;  // black
    expect_matches_reference(map, 24, "negative values");
}

}  // namespace
}  // namespace penumbra::lights
