// Blender's Environment Texture lookup and the World resampled onto a latlong
// grid (image/environment_lookup.hpp), against what follows from the
// conventions independently: a grid of the image's own size is the image, a
// quarter turn about z rolls its columns by a quarter, Cycles' mirror-ball
// formula written out here, flux kept, uniform terms added everywhere; and
// its bad input and cancel. (Cycles' own panorama of remapped Worlds is the
// reference in tests/blender/test_world.py.)
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "common/error.hpp"
#include "common/latlong.hpp"
#include "image/environment_lookup.hpp"

namespace penumbra {
namespace {

// Every pixel different: R = column, G = row, B = 1.
Image coordinate_image(int width, int height) {
    Image image(width, height, 3);
    for (int r = 0; r < height; ++r)
        for (int c = 0; c < width; ++c) {
            image.at(c, r, 0) = float(c);
            image.at(c, r, 1) = float(r);
            image.at(c, r, 2) = 1.0f;
        }
    return image;
}

EnvironmentTerm image_term(const Image& image, bool closest) {
    EnvironmentTerm term;
    term.image = &image;
    term.closest = closest;
    return term;
}

TEST(EnvironmentLookup, a_grid_of_the_images_own_size_is_the_image) {
    const Image image = coordinate_image(16, 8);
    for (const bool closest : {true, false}) {
        const Image grid = environment_radiance({image_term(image, closest)}, 16, 1);
        ASSERT_EQ(grid.width, 16);
        ASSERT_EQ(grid.height, 8);
        for (std::size_t i = 0; i < grid.pixels.size(); ++i)
            ASSERT_NEAR(grid.pixels[i], image.pixels[i], 2e-5) << "closest " << closest << " value " << i;
    }
}

TEST(EnvironmentLookup, a_quarter_turn_about_z_rolls_the_columns_by_a_quarter) {
    const Image image = coordinate_image(16, 8);
    EnvironmentTerm term = image_term(image, true);
    LookupStep turn;  // m = Rz(90°)·d: what the map shows at m is seen at d = Rz(−90°)·m
    turn.a << 0, -1, 0, 1, 0, 0, 0, 0, 1;
    term.steps.push_back(turn);
    const Image grid = environment_radiance({term}, 16, 1);
    // φ(m) = φ(d) + 90°, and x = W(½ − φ/2π): 4 columns to the left.
    for (int r = 0; r < 8; ++r)
        for (int c = 0; c < 16; ++c) {
            EXPECT_FLOAT_EQ(grid.at(c, r, 0), float((c + 16 - 4) % 16)) << r << " " << c;
            EXPECT_FLOAT_EQ(grid.at(c, r, 1), float(r));
        }
}

TEST(EnvironmentLookup, mirror_ball_follows_cycles_direction_to_mirrorball) {
    const Image ball = coordinate_image(64, 64);
    for (const Eigen::Vector3d& m : {Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(1, 0, 0),
                                     Eigen::Vector3d(0.3, -0.5, 0.8).normalized()}) {
        // kernel/camera/projection.h: direction_to_mirrorball, v = 0 at the bottom.
        const Eigen::Vector3d n(m.x(), m.y() - 1.0, m.z());
        const double div = 2.0 * std::sqrt(std::max(-0.5 * n.y(), 0.0));
        const double u = 0.5 * (n.x() / div + 1.0), v = 0.5 * (n.z() / div + 1.0);
        const Eigen::Vector3f got = texture_lookup(ball, m, EnvironmentProjection::mirror_ball, true);
        EXPECT_EQ(got.x(), std::floor(float(u * 64))) << m.transpose();
        EXPECT_EQ(got.y(), 63 - std::floor(float(v * 64))) << m.transpose();  // row 0 = the top
    }
}

TEST(EnvironmentLookup, a_small_suns_flux_survives_the_resampling_and_a_uniform_scale_changes_nothing) {
    // A uniform scale changes only the vector's length: the same World.
    Image map(64, 32, 3);
    map.at(40, 10, 0) = map.at(40, 10, 1) = map.at(40, 10, 2) = 1000.0f;
    EnvironmentTerm plain = image_term(map, false), scaled = plain;
    LookupStep scale;
    scale.a = 3.0 * Eigen::Matrix3d::Identity();
    scaled.steps.push_back(scale);
    const Image a = environment_radiance({plain}, 128, 2), b = environment_radiance({scaled}, 128, 2);
    double flux_a = 0.0, flux_b = 0.0, flux_map = 0.0;
    for (int r = 0; r < a.height; ++r)
        for (int c = 0; c < a.width; ++c) {
            flux_a += a.at(c, r, 0) * latlong::pixel_solid_angle(r, a.height, a.width);
            flux_b += b.at(c, r, 0) * latlong::pixel_solid_angle(r, b.height, b.width);
        }
    flux_map = 1000.0 * latlong::pixel_solid_angle(10, 32, 64);
    EXPECT_NEAR(flux_a, flux_map, 0.02 * flux_map);
    EXPECT_NEAR(flux_b, flux_a, 1e-6 * flux_a);
}

TEST(EnvironmentLookup, uniform_terms_add_their_scaled_colour_everywhere) {
    const Image image = coordinate_image(8, 4);
    EnvironmentTerm colour, pixels = image_term(image, true);
    colour.colour = {0.5, 1.0, 2.0};
    colour.scale = 3.0;
    pixels.scale = 0.5;
    const Image grid = environment_radiance({colour, pixels}, 8, 1);
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 8; ++c) {
            EXPECT_FLOAT_EQ(grid.at(c, r, 0), 1.5f + 0.5f * float(c));
            EXPECT_FLOAT_EQ(grid.at(c, r, 2), 6.0f + 0.5f);
        }
}

TEST(EnvironmentLookup, a_vector_that_comes_out_zero_looks_up_m_equal_zero) {
    EnvironmentTerm term;
    LookupStep collapse;
    collapse.a.setZero();
    term.steps.push_back(collapse);
    EXPECT_EQ(lookup_direction(term.steps, Eigen::Vector3d::UnitX()), Eigen::Vector3d::Zero());
}

TEST(EnvironmentLookup, bad_input_is_an_argument_error) {
    const Image grey(4, 2, 1), image = coordinate_image(4, 2);
    EXPECT_THROW(environment_radiance({}, 1), ArgumentError);
    EXPECT_THROW(environment_radiance({image_term(image, false)}, 8, 0), ArgumentError);
    EXPECT_THROW(environment_radiance({image_term(grey, false)}, 8), ArgumentError);
    EnvironmentTerm nan_scale = image_term(image, false);
    nan_scale.scale = std::nan("");
    EXPECT_THROW(environment_radiance({nan_scale}, 8), ArgumentError);
    EnvironmentTerm inf_step = image_term(image, false);
    inf_step.steps.push_back(LookupStep{});
    inf_step.steps.back().b.x() = INFINITY;
    EXPECT_THROW(environment_radiance({inf_step}, 8), ArgumentError);
}

TEST(EnvironmentLookup, cancel_stops_with_cancelled) {
    const Image image = coordinate_image(64, 32);
    const Progress stop([](double) { return false; });
    EXPECT_THROW(environment_radiance({image_term(image, false)}, 1024, 2, 1, stop), Cancelled);
}

}  // namespace
}  // namespace penumbra
