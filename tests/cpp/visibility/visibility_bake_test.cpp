// Ray casting and per-frame visibility (visibility/visibility_bake.hpp),
// checked against a brute-force ray tracer written here (Möller–Trumbore over
// every triangle, no Embree) and against closed forms (a lone convex sphere
// sees exactly its upper hemisphere); merging a farm's training-set pieces.
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <gtest/gtest.h>

#include "common/error.hpp"
#include "sh/basis.hpp"
#include "sh/point_sets.hpp"
#include "sh/zonal.hpp"
#include "visibility/mesh_frames.hpp"
#include "visibility/visibility_bake.hpp"
#include "visibility/zh_fit.hpp"
#include "visibility_test_util.hpp"

namespace penumbra::visibility {
namespace {

using testing::TestMesh;
using testing::add_sphere;
using testing::synthetic_set;

bool brute_force_occluded(const TriangleMesh& mesh, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
        Eigen::Vector3d v[3];
        for (int k = 0; k < 3; ++k) {
            const auto i = mesh.triangles[3 * t + k];
            v[k] = Eigen::Vector3d(mesh.positions[3 * i], mesh.positions[3 * i + 1], mesh.positions[3 * i + 2]);
        }
        const Eigen::Vector3d e1 = v[1] - v[0], e2 = v[2] - v[0], p = d.cross(e2);
        const double det = e1.dot(p);
        if (std::abs(det) < 1e-14) continue;
        const Eigen::Vector3d s = o - v[0];
        const double u = s.dot(p) / det;
        if (u < 0 || u > 1) continue;
        const Eigen::Vector3d q = s.cross(e1);
        const double w = d.dot(q) / det;
        if (w < 0 || u + w > 1) continue;
        if (e2.dot(q) / det > 0) return true;
    }
    return false;
}

TestMesh two_spheres() {
    TestMesh m;
    add_sphere(m, Eigen::Vector3d::Zero(), 1.0);
    add_sphere(m, Eigen::Vector3d(1.5, 0.2, 0.1), 0.6, 16, 8);
    return m;
}

FrameGeometry geometry_of(const TestMesh& m) {
    FrameGeometry g;
    g.mesh = m.mesh;
    g.normals = m.normals;
    return g;
}

TEST(VisibilityBake, packets_agree_with_single_rays_and_with_brute_force) {
    const TestMesh m = two_spheres();
    const OcclusionScene scene({&m.mesh});
    const sh::PointSet dirs = sh::fibonacci_sphere(64);
    std::vector<Eigen::Vector3f> d;
    for (const auto& x : dirs.directions) d.push_back(x.cast<float>());
    int disagreements = 0, checked = 0;
    for (std::size_t v = 0; v < m.mesh.vertex_count(); v += 7) {
        const Eigen::Vector3f n(m.normals[3 * v], m.normals[3 * v + 1], m.normals[3 * v + 2]);
        const Eigen::Vector3f o = Eigen::Vector3f(m.mesh.positions[3 * v], m.mesh.positions[3 * v + 1],
                                                  m.mesh.positions[3 * v + 2]) + 1e-3f * n;
        std::vector<std::uint8_t> hit(d.size());
        scene.occluded_bundle(o, d.data(), int(d.size()), 0.0f, INFINITY, hit.data(), true);
        for (std::size_t i = 0; i < d.size(); ++i) {
            EXPECT_EQ(bool(hit[i]), scene.occluded1(o, d[i], 0.0f, INFINITY));
            disagreements += bool(hit[i]) != brute_force_occluded(m.mesh, o.cast<double>(), d[i].cast<double>());
            ++checked;
        }
    }
    // Grazing rays may go either way; almost all must agree.
    EXPECT_LT(disagreements, checked / 200 + 2) << disagreements << " of " << checked;
}

TEST(VisibilityBake, frame_visibility_matches_a_brute_force_projection) {
    const TestMesh m = two_spheres();
    BakeSettings s;
    s.rays = 64;
    s.below_horizon = BelowHorizon::Cast;
    const auto neighbours = reference_neighbours(m.mesh.vertex_count(), {}, m.mesh.triangles);
    std::vector<float> vis(m.mesh.vertex_count() * 16);
    bake_frame(geometry_of(m), neighbours, s, vis.data());
    const RaySet rays = make_ray_set(s);
    std::vector<float> frames(9 * m.mesh.vertex_count());
    vertex_frames(m.mesh.positions, m.normals, m.mesh.triangles, neighbours, frames.data());
    const double offset = 1e-4 * mesh_diagnostics(m.mesh.positions, m.normals, {}).bounding_diagonal;
    double worst = 0.0;
    for (std::size_t v = 0; v < m.mesh.vertex_count(); v += 5) {
        const float* f = frames.data() + 9 * v;
        const Eigen::Vector3d t(f[0], f[1], f[2]), b(f[3], f[4], f[5]), n(f[6], f[7], f[8]);
        const Eigen::Vector3d p(m.mesh.positions[3 * v], m.mesh.positions[3 * v + 1], m.mesh.positions[3 * v + 2]);
        std::vector<double> expected(16, 0.0);
        for (int i = 0; i < s.rays; ++i) {
            const Eigen::Vector3d dl = rays.directions[i].cast<double>();
            const Eigen::Vector3d dw = dl.x() * t + dl.y() * b + dl.z() * n;
            const Eigen::Vector3d o = p + (i < rays.upper ? offset : -offset) * n;
            if (brute_force_occluded(m.mesh, o, dw)) continue;
            for (int k = 0; k < 16; ++k) expected[k] += rays.projection[i * 16 + k];
        }
        for (int k = 0; k < 16; ++k) worst = std::max(worst, std::abs(expected[k] - vis[v * 16 + k]));
    }
    // One grazing ray flipping changes a coefficient by at most 4π/64·|y| < 0.1.
    EXPECT_LT(worst, 0.1);
}

TEST(VisibilityBake, lone_sphere_sees_exactly_its_upper_hemisphere) {
    TestMesh m;
    add_sphere(m, Eigen::Vector3d::Zero(), 1.0, 32, 16);
    BakeSettings s;
    s.rays = 4096;
    const auto neighbours = reference_neighbours(m.mesh.vertex_count(), {}, m.mesh.triangles);
    std::vector<float> vis(m.mesh.vertex_count() * 16);
    bake_frame(geometry_of(m), neighbours, s, vis.data());
    // Closed form: the indicator of cosθ > 0 about +z, projected by Gauss–Legendre.
    const auto band = sh::project_zonal(4, [](double mu) { return mu > 0 ? 1.0 : 0.0; }, 256);
    for (std::size_t v = 0; v < m.mesh.vertex_count(); v += 13) {
        for (int l = 0; l < 4; ++l)
            for (int mm = -l; mm <= l; ++mm) {
                const double expected = mm == 0 ? band[l] : 0.0;
                EXPECT_NEAR(vis[v * 16 + sh::sh_index(l, mm)], expected, 0.03) << "vertex " << v << " l " << l;
            }
        double sh[16];
        for (int k = 0; k < 16; ++k) sh[k] = vis[v * 16 + k];
        EXPECT_NEAR(ambient_occlusion(4, sh), 1.0, 0.01);
    }
}

TEST(VisibilityBake, results_do_not_depend_on_scale_from_1e_minus_3_to_1e4) {
    const TestMesh base = two_spheres();
    BakeSettings s;
    s.rays = 64;
    const auto neighbours = reference_neighbours(base.mesh.vertex_count(), {}, base.mesh.triangles);
    std::vector<float> reference(base.mesh.vertex_count() * 16);
    bake_frame(geometry_of(base), neighbours, s, reference.data());
    for (double scale : {1e-3, 1e4}) {
        TestMesh m = base;
        for (auto& x : m.mesh.positions) x = float(x * scale);
        for (std::size_t i = 0; i < m.mesh.positions.size(); i += 3) m.mesh.positions[i] += float(7.0 * scale);
        std::vector<float> vis(reference.size());
        bake_frame(geometry_of(m), neighbours, s, vis.data());
        std::size_t differing = 0;
        for (std::size_t v = 0; v < m.mesh.vertex_count(); ++v) {
            double d = 0;
            for (int k = 0; k < 16; ++k) d += std::abs(vis[v * 16 + k] - reference[v * 16 + k]);
            differing += d > 1e-4;
        }
        EXPECT_LT(differing, m.mesh.vertex_count() / 50) << "scale " << scale;
    }
}

TEST(VisibilityBake, occluders_shadow_the_mesh) {
    TestMesh m;
    add_sphere(m, Eigen::Vector3d::Zero(), 1.0);
    TestMesh blocker;
    add_sphere(blocker, Eigen::Vector3d(0, 0, 1.6), 0.5);
    BakeSettings s;
    s.rays = 256;
    const auto neighbours = reference_neighbours(m.mesh.vertex_count(), {}, m.mesh.triangles);
    FrameGeometry g = geometry_of(m);
    std::vector<float> open(m.mesh.vertex_count() * 16), shadowed(open.size());
    bake_frame(g, neighbours, s, open.data());
    g.occluders.push_back(blocker.mesh);
    bake_frame(g, neighbours, s, shadowed.data());
    double top_open[16], top_shadowed[16];
    for (int k = 0; k < 16; ++k) top_open[k] = open[k], top_shadowed[k] = shadowed[k];  // vertex 0: the pole
    EXPECT_NEAR(ambient_occlusion(4, top_open), 1.0, 0.02);
    EXPECT_LT(ambient_occlusion(4, top_shadowed), 0.7);
}

TEST(VisibilityBake, frame_baker_reuses_its_scene_and_matches_fresh_bakes_frame_after_frame) {
    // A sphere shadowed by a second one that moves from frame to frame (same
    // structure: the baker only updates the vertex buffers), then a frame with
    // another occluder structure (rebuilt). Every frame must equal a bake from
    // scratch, at every scene build.
    TestMesh m;
    add_sphere(m, Eigen::Vector3d::Zero(), 1.0);
    const auto neighbours = reference_neighbours(m.mesh.vertex_count(), {}, m.mesh.triangles);
    BakeSettings s;
    s.rays = 128;
    for (SceneBuild build : {SceneBuild::High, SceneBuild::Medium, SceneBuild::Low, SceneBuild::Refit}) {
        FrameBaker baker(s, build);
        for (int f = 0; f < 4; ++f) {
            TestMesh blocker;
            if (f < 3) add_sphere(blocker, Eigen::Vector3d(0.8 * f - 0.8, 0, 1.7), 0.5);
            else add_sphere(blocker, Eigen::Vector3d(0, 0, 1.7), 0.5, 12, 6);  // other structure
            FrameGeometry g = geometry_of(m);
            g.occluders.push_back(blocker.mesh);
            std::vector<float> kept(m.mesh.vertex_count() * 16), fresh(kept.size());
            FrameBakeStats stats;
            baker.bake(g, neighbours, kept.data(), {}, &stats);
            bake_frame(g, neighbours, s, fresh.data());
            EXPECT_EQ(stats.scene_updated, f == 1 || f == 2) << "frame " << f;
            for (std::size_t i = 0; i < kept.size(); ++i) ASSERT_EQ(kept[i], fresh[i]) << "frame " << f << " value " << i;
        }
    }
}

TEST(VisibilityBake, fast_traversal_bakes_what_robust_traversal_bakes) {
    // The bake's default is Embree's fast arithmetic (Traversal::Fast). On
    // closed meshes, with rays from just above the surface and, cast, from
    // just below it (those cross the skin's edges near the vertex), at three
    // scales, it must give the robust traversal's visibility bit for bit.
    for (double scale : {1e-3, 1.0, 1e4}) {
        TestMesh m;
        add_sphere(m, Eigen::Vector3d::Zero(), scale, 12, 6);
        add_sphere(m, Eigen::Vector3d(1.5, 0.2, 0.1) * scale, 0.6 * scale, 24, 12);
        const auto neighbours = reference_neighbours(m.mesh.vertex_count(), {}, m.mesh.triangles);
        BakeSettings s;
        s.rays = 1024;
        s.below_horizon = BelowHorizon::Cast;
        std::vector<float> fast(m.mesh.vertex_count() * 16), robust(fast.size());
        FrameBaker(s, SceneBuild::Medium, Traversal::Fast).bake(geometry_of(m), neighbours, fast.data());
        FrameBaker(s, SceneBuild::Medium, Traversal::Robust).bake(geometry_of(m), neighbours, robust.data());
        for (std::size_t i = 0; i < fast.size(); ++i) ASSERT_EQ(fast[i], robust[i]) << "scale " << scale << " value " << i;
    }
}

TEST(VisibilityBake, robust_traversal_lets_no_ray_through_shared_edges) {
    // From inside a closed sphere every ray is blocked, also one aimed
    // exactly at a vertex or along an edge, where a non-watertight test can
    // slip between the two triangles (Embree's fast arithmetic does, for a
    // few % of such rays): the robust traversal the option asks for must not.
    TestMesh m;
    const Eigen::Vector3d centre(0.3, 0.1, -0.2);
    add_sphere(m, centre, 1.0, 24, 12);
    const OcclusionScene robust({&m.mesh}, SceneBuild::Medium, Traversal::Robust);
    const Eigen::Vector3f c = centre.cast<float>();
    int leaks = 0, rays = 0;
    for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t)
        for (int k = 0; k < 3; ++k) {
            const auto corner = [&](int j) {
                const auto i = m.mesh.triangles[3 * t + (k + j) % 3];
                return Eigen::Vector3f(m.mesh.positions[3 * i], m.mesh.positions[3 * i + 1], m.mesh.positions[3 * i + 2]);
            };
            for (int step = 0; step < 10; ++step, ++rays)
                leaks += !robust.occluded1(c, corner(0) + (step / 10.0f) * (corner(1) - corner(0)) - c, 0.0f, INFINITY);
        }
    EXPECT_EQ(leaks, 0) << "of " << rays;
}

TEST(VisibilityBake, updated_scene_answers_at_the_new_positions) {
    TestMesh m;
    add_sphere(m, Eigen::Vector3d(0, 0, 5), 1.0);
    OcclusionScene scene({&m.mesh});
    const Eigen::Vector3f up(0, 0, 1);
    EXPECT_TRUE(scene.occluded1(Eigen::Vector3f::Zero(), up, 0.0f, 100.0f));
    TestMesh moved;
    add_sphere(moved, Eigen::Vector3d(5, 0, 0), 1.0);
    ASSERT_TRUE(scene.update_positions({&moved.mesh}));
    EXPECT_FALSE(scene.occluded1(Eigen::Vector3f::Zero(), up, 0.0f, 100.0f));
    EXPECT_TRUE(scene.occluded1(Eigen::Vector3f::Zero(), Eigen::Vector3f(1, 0, 0), 0.0f, 100.0f));
    // Another structure is refused and leaves the scene as it was.
    TestMesh other;
    add_sphere(other, Eigen::Vector3d(0, 0, 5), 1.0, 12, 6);
    EXPECT_FALSE(scene.update_positions({&other.mesh}));
    EXPECT_FALSE(scene.update_positions({&moved.mesh, &moved.mesh}));
    EXPECT_TRUE(scene.occluded1(Eigen::Vector3f::Zero(), Eigen::Vector3f(1, 0, 0), 0.0f, 100.0f));
    // A non-finite position is an error, the scene untouched.
    TestMesh bad = moved;
    bad.mesh.positions[4] = NAN;
    EXPECT_THROW(scene.update_positions({&bad.mesh}), ArgumentError);
    EXPECT_TRUE(scene.occluded1(Eigen::Vector3f::Zero(), Eigen::Vector3f(1, 0, 0), 0.0f, 100.0f));
}

TEST(VisibilityBake, inward_normals_are_detected) {
    TestMesh m;
    add_sphere(m, Eigen::Vector3d::Zero(), 1.0);
    EXPECT_FALSE(mesh_diagnostics(m.mesh.positions, m.normals, m.mesh.triangles).normals_point_inward);
    for (std::size_t t = 0; t < m.mesh.triangles.size(); t += 3) std::swap(m.mesh.triangles[t + 1], m.mesh.triangles[t + 2]);
    for (auto& n : m.normals) n = -n;
    const auto d = mesh_diagnostics(m.mesh.positions, m.normals, m.mesh.triangles);
    EXPECT_TRUE(d.normals_point_inward);
    EXPECT_LT(d.signed_volume, 0.0);
}

TEST(VisibilityBake, zero_area_faces_and_zero_normals_give_finite_visibility) {
    TestMesh m;
    add_sphere(m, Eigen::Vector3d::Zero(), 1.0);
    // A degenerate triangle (all three corners at one new vertex) and zeroed normals.
    const auto extra = std::uint32_t(m.mesh.vertex_count());
    for (int k = 0; k < 3; ++k) m.mesh.positions.push_back(0.5f), m.normals.push_back(0.0f);
    m.mesh.triangles.insert(m.mesh.triangles.end(), {extra, extra, extra});
    m.normals[3] = m.normals[4] = m.normals[5] = 0.0f;
    m.normals[6] = NAN;
    const auto d = mesh_diagnostics(m.mesh.positions, m.normals, m.mesh.triangles);
    EXPECT_EQ(d.zero_area_triangles, 1u);
    EXPECT_EQ(d.zero_length_normals, 3u);
    const auto neighbours = reference_neighbours(m.mesh.vertex_count(), {}, m.mesh.triangles);
    BakeSettings s;
    s.rays = 64;
    std::vector<float> vis(m.mesh.vertex_count() * 16);
    FrameBakeStats stats;
    bake_frame(geometry_of(m), neighbours, s, vis.data(), {}, &stats);
    EXPECT_EQ(stats.frames.repaired_normals, 3u);
    for (float x : vis) EXPECT_TRUE(std::isfinite(x));
}

TEST(VisibilityBake, empty_mesh_bakes_nothing_and_bad_indices_are_errors) {
    FrameGeometry g;
    std::vector<float> none;
    EXPECT_NO_THROW(bake_frame(g, {}, BakeSettings{}, none.data()));
    TestMesh m;
    add_sphere(m, Eigen::Vector3d::Zero(), 1.0);
    m.mesh.triangles.push_back(999999);
    m.mesh.triangles.push_back(0);
    m.mesh.triangles.push_back(1);
    EXPECT_THROW(reference_neighbours(m.mesh.vertex_count(), {}, m.mesh.triangles), ArgumentError);
    EXPECT_THROW(OcclusionScene({&m.mesh}), ArgumentError);
}

TEST(VisibilityBake, settings_out_of_range_are_argument_errors) {
    BakeSettings s;
    s.rays = 2;
    EXPECT_THROW(check_bake_settings(s), ArgumentError);
    s = {};
    s.order = 9;
    EXPECT_THROW(check_bake_settings(s), ArgumentError);
    s = {};
    s.offset_scale = 0.0;
    EXPECT_THROW(check_bake_settings(s), ArgumentError);
}

TEST(VisibilityBake, cancel_from_progress_throws_cancelled) {
    TestMesh m;
    add_sphere(m, Eigen::Vector3d::Zero(), 1.0, 64, 32);
    const auto neighbours = reference_neighbours(m.mesh.vertex_count(), {}, m.mesh.triangles);
    BakeSettings s;
    s.rays = 1024;
    std::vector<float> vis(m.mesh.vertex_count() * 16);
    const Progress stop([](double) { return false; });
    EXPECT_THROW(bake_frame(geometry_of(m), neighbours, s, vis.data(), stop), Cancelled);
}

TEST(VisibilityBake, merging_pieces_sorts_frames_and_rejects_foreign_pieces) {
    TrainingSet a = synthetic_set({0.0, 0.1}, 4), b = synthetic_set({0.2, 0.3}, 4);
    for (auto& f : a.frames) f.frame += 10;
    const TrainingSet merged = merge_training_sets({a, b});
    ASSERT_EQ(merged.frames.size(), 4u);
    EXPECT_EQ(merged.frames[0].frame, 0.0);
    EXPECT_EQ(merged.frames[3].frame, 11.0);
    TrainingSet other = b;
    other.topology_hash = 7;
    EXPECT_THROW(merge_training_sets({a, other}), ArgumentError);
    other = b;
    other.bone_names = {"leg"};
    EXPECT_THROW(merge_training_sets({a, other}), ArgumentError);
    other = b;
    other.settings.rays = 128;
    EXPECT_THROW(merge_training_sets({a, other}), ArgumentError);
}

}  // namespace
}  // namespace penumbra::visibility
