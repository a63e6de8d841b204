// The fused frame shading (visibility/frame_shading.hpp) and Blender's vertex
// normals (visibility/vertex_normals.hpp): against straightforward
// double-precision versions of the same rules, against the separate-pass
// path with the same inputs, and across SIMD targets and thread counts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "common/error.hpp"
#include "common/simd_target.hpp"
#include "sh/pose_shading.hpp"
#include "visibility/frame_shading.hpp"
#include "visibility/vertex_normals.hpp"
#include "visibility/zh_fit.hpp"

namespace penumbra::visibility {
namespace {

// A bumpy closed grid: a UV sphere of quads with triangle fans at the poles,
// one pentagon made by merging two quads, and a loose vertex at the end;
// positions jittered so corner angles and face areas vary (angle and area
// weighting then disagree).
struct Polygons {
    std::vector<float> positions;
    std::vector<std::uint32_t> sizes, loops;
    std::size_t vertex_count() const { return positions.size() / 3; }
};

Polygons bumpy_sphere(int rings, int segments, std::mt19937_64& rng) {
    std::uniform_real_distribution<double> jitter(-0.15, 0.15);
    Polygons m;
    const auto push = [&](double x, double y, double z) {
        const double r = 1.0 + jitter(rng);
        for (const double c : {x * r, y * r, z * r}) m.positions.push_back(float(c));
    };
    push(0, 0, 1);
    for (int r = 1; r < rings; ++r)
        for (int s = 0; s < segments; ++s) {
            const double th = M_PI * r / rings, ph = 2 * M_PI * (s + 0.3 * jitter(rng)) / segments;
            push(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
        }
    push(0, 0, -1);
    const auto ring = [&](int r, int s) { return std::uint32_t(1 + (r - 1) * segments + (s + segments) % segments); };
    const std::uint32_t south = std::uint32_t(m.vertex_count() - 1);
    const auto face = [&](std::initializer_list<std::uint32_t> corners) {
        m.sizes.push_back(std::uint32_t(corners.size()));
        m.loops.insert(m.loops.end(), corners);
    };
    for (int s = 0; s < segments; ++s) face({0, ring(1, s), ring(1, s + 1)});
    for (int r = 1; r + 1 < rings; ++r)
        for (int s = 0; s < segments; ++s) {
            if (r == 2 && s == 1) continue;  // merged into the pentagon below
            if (r == 2 && s == 0) {
                face({ring(r, s), ring(r + 1, s), ring(r + 1, s + 1), ring(r + 1, s + 2), ring(r, s + 2)});
                continue;
            }
            face({ring(r, s), ring(r + 1, s), ring(r + 1, s + 1), ring(r, s + 1)});
        }
    for (int s = 0; s < segments; ++s) face({south, ring(rings - 1, s + 1), ring(rings - 1, s)});
    push(0.3, 0.2, 0.1);  // used by no face
    return m;
}

Eigen::Vector3d point(const Polygons& m, std::uint32_t v) {
    return Eigen::Vector3d(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]);
}

// Blender's rule in double, written from its definition: angle-weighted
// (exact arc cosine) unit face normals by Newell's method.
std::vector<Eigen::Vector3d> reference_normals(const Polygons& m, bool area_weighted = false) {
    std::vector<Eigen::Vector3d> sum(m.vertex_count(), Eigen::Vector3d::Zero());
    std::size_t start = 0;
    for (const std::uint32_t size : m.sizes) {
        Eigen::Vector3d newell = Eigen::Vector3d::Zero();
        for (std::uint32_t c = 0; c < size; ++c)
            newell += point(m, m.loops[start + (c + size - 1) % size]).cross(point(m, m.loops[start + c]));
        const Eigen::Vector3d normal = newell.normalized();
        for (std::uint32_t c = 0; c < size; ++c) {
            const std::uint32_t v = m.loops[start + c];
            const Eigen::Vector3d a = (point(m, m.loops[start + (c + size - 1) % size]) - point(m, v)).normalized();
            const Eigen::Vector3d b = (point(m, m.loops[start + (c + 1) % size]) - point(m, v)).normalized();
            sum[v] += area_weighted ? newell : Eigen::Vector3d(normal * std::acos(std::clamp(a.dot(b), -1.0, 1.0)));
        }
        start += size;
    }
    for (std::size_t v = 0; v < sum.size(); ++v)
        sum[v] = sum[v].norm() > 0 ? sum[v].normalized() : point(m, std::uint32_t(v)).normalized();
    return sum;
}

TEST(VertexNormals, follow_blenders_angle_weighted_rule) {
    std::mt19937_64 rng(1);
    const Polygons m = bumpy_sphere(9, 13, rng);
    const PolygonMesh mesh(m.vertex_count(), m.sizes, m.loops);
    std::vector<float> normals(m.positions.size());
    mesh.vertex_normals(m.positions.data(), normals.data());
    const std::vector<Eigen::Vector3d> angle = reference_normals(m), area = reference_normals(m, true);
    double largest = 0.0, area_gap = 0.0;
    for (std::size_t v = 0; v < m.vertex_count(); ++v) {
        const Eigen::Vector3d n(normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]);
        largest = std::max(largest, (n - angle[v]).norm());
        area_gap = std::max(area_gap, (area[v] - angle[v]).norm());
    }
    // The arc cosine is Blender's polynomial (error ≤ 4.5e-5 rad on each
    // weight); the mesh is uneven enough that area weighting is far off.
    EXPECT_LT(largest, 1e-4);
    EXPECT_GT(area_gap, 1e-2);
    // The loose vertex: its normalized position.
    const std::size_t loose = m.vertex_count() - 1;
    EXPECT_NEAR(normals[3 * loose], float(point(m, std::uint32_t(loose)).normalized().x()), 1e-7);
}

TEST(VertexNormals, every_simd_target_gives_the_same_normals_bit_for_bit) {
    std::mt19937_64 rng(2);
    const Polygons m = bumpy_sphere(12, 37, rng);  // 37: partial batches of quads and triangles
    const PolygonMesh mesh(m.vertex_count(), m.sizes, m.loops);
    std::vector<float> first;
    for (const std::string& target : simd_targets()) {
        force_simd_target(target);
        std::vector<float> normals(m.positions.size());
        mesh.vertex_normals(m.positions.data(), normals.data(), 2);
        if (first.empty()) first = normals;
        EXPECT_EQ(normals, first) << target;
    }
    force_simd_target("");
}

TEST(VertexNormals, bad_polygons_are_argument_errors) {
    EXPECT_THROW(PolygonMesh(4, {4}, {0, 1, 2}), ArgumentError);
    EXPECT_THROW(PolygonMesh(3, {3}, {0, 1, 3}), ArgumentError);
    EXPECT_THROW(PolygonMesh(3, {2}, {0, 1}), ArgumentError);
}

// A model of `joints` joints over the mesh: every third vertex constant, the
// others with one or two joint blocks.
PoseModel random_model(std::size_t vertices, int joints, std::mt19937_64& rng) {
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    PoseModel m;
    m.order = 4;
    m.lobes = 2;
    m.vertex_count = vertices;
    for (int j = 0; j < joints; ++j) m.joints.push_back("bone" + std::to_string(j));
    const int d = m.params_per_vertex();
    m.joint_offsets.push_back(0);
    for (std::size_t v = 0; v < vertices; ++v) {
        for (std::size_t k = 0; k < v % 3; ++k) m.joint_index.push_back(std::uint16_t((v + k) % joints));
        m.joint_offsets.push_back(std::uint32_t(m.joint_index.size()));
    }
    m.bias.resize(vertices * d);
    for (std::size_t i = 0; i < m.bias.size(); ++i) m.bias[i] = (i % 6 < 2 ? 0.8f : 1.5f) * uniform(rng);
    std::vector<float> weights(m.joint_index.size() * 9 * d);
    for (float& w : weights) w = 0.2f * uniform(rng);
    use_raw_joint_features(m);
    set_weights(m, weights);
    return m;
}

std::vector<float> random_rotations(int joints, std::mt19937_64& rng) {
    std::uniform_real_distribution<double> angle(-1.0, 1.0);
    std::vector<float> r;
    for (int j = 0; j < joints; ++j) {
        const Eigen::Matrix3d m = Eigen::AngleAxisd(angle(rng), Eigen::Vector3d(angle(rng), angle(rng), 1).normalized())
                                      .toRotationMatrix();
        for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k) r.push_back(float(m(i, k)));
    }
    return r;
}

struct FrameCase {
    Polygons polygons;
    PoseModel model;
    std::vector<float> rotations;
    Eigen::Matrix4d world = Eigen::Matrix4d::Identity();
    Eigen::MatrixXd lighting;
    sh::ShadingParameters parameters;
};

FrameCase frame_case(std::mt19937_64& rng, sh::ShadingModel shading) {
    FrameCase c;
    c.polygons = bumpy_sphere(14, 23, rng);
    c.model = random_model(c.polygons.vertex_count(), 3, rng);
    c.rotations = random_rotations(3, rng);
    // Rotated, non-uniformly scaled, moved: normals go by the inverse transpose.
    c.world.topLeftCorner<3, 3>() =
        Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix() *
        Eigen::Vector3d(1.0, 1.7, 0.6).asDiagonal();
    c.world.topRightCorner<3, 1>() = Eigen::Vector3d(0.4, -1.2, 2.0);
    c.lighting = Eigen::MatrixXd::Random(16, 3);
    c.lighting.row(0).array() += 2.0;
    c.parameters.model = shading;
    c.parameters.phong_exponent = 9.0;
    c.parameters.camera = Eigen::Vector3d(3.0, -2.0, 4.0);
    c.parameters.transmission = {0.5, 0.3, 0.2};
    c.parameters.threads = 2;
    return c;
}

// One model of shading on the current target: shade_frame against
// shade_pose_model given the same normals (the rule's, moved to world space
// here) and world positions.
void expect_fused_frame_matches_separate_passes(std::mt19937_64& rng, sh::ShadingModel shading,
                                                const std::string& target) {
    const FrameCase c = frame_case(rng, shading);
    const std::size_t V = c.polygons.vertex_count();
    const ShadingMesh mesh(V, c.polygons.sizes, c.polygons.loops);
    const sh::PoseShader shader(4);
    std::vector<float> rgba(4 * V, -1.0f), ao(V, -1.0f);
    const FrameResult fused = shade_frame(c.model, shader, mesh, c.rotations.data(), c.polygons.positions.data(),
                                          c.world, c.lighting, c.parameters, rgba.data(), ao.data());

    std::vector<float> local(3 * V), world_positions(3 * V), world_normals(3 * V);
    mesh.polygons.vertex_normals(c.polygons.positions.data(), local.data());
    const Eigen::Matrix3d linear = c.world.topLeftCorner<3, 3>(), normal_matrix = linear.inverse().transpose();
    for (std::size_t v = 0; v < V; ++v) {
        const Eigen::Vector3d p = linear * point(c.polygons, std::uint32_t(v)) + c.world.topRightCorner<3, 1>();
        const Eigen::Vector3d n = normal_matrix * Eigen::Vector3d(local[3 * v], local[3 * v + 1], local[3 * v + 2]);
        for (int k = 0; k < 3; ++k) {
            world_positions[3 * v + k] = float(p[k]);
            world_normals[3 * v + k] = float(n[k]);
        }
    }
    const ShadingResult separate = shade_pose_model(c.model, shader, c.rotations.data(), world_positions,
                                                    world_normals, {}, mesh.neighbours, c.lighting, c.parameters);
    EXPECT_EQ(fused.stats.invalid_vertices, separate.stats.invalid_vertices);
    double largest = 0.0, scale = 0.0;
    bool clamped = false;
    for (std::size_t v = 0; v < V; ++v) {
        for (int k = 0; k < 3; ++k) {
            const float expected = std::max(separate.rgb[3 * v + k], 0.0f);
            clamped |= separate.rgb[3 * v + k] < 0.0f;
            largest = std::max(largest, double(std::abs(rgba[4 * v + k] - expected)));
            scale = std::max(scale, double(expected));
        }
        EXPECT_EQ(rgba[4 * v + 3], 1.0f);
        const float expected_ao = std::clamp(separate.visibility[v], 0.0f, 1.0f);
        largest = std::max(largest, double(std::abs(ao[v] - expected_ao)));
    }
    // The same float kernel; the frames differ by float rounding only
    // (float lanes here, double in shade_pose_model's vertex_frames).
    EXPECT_LT(largest, 2e-5 * scale) << target << " " << int(shading);
    EXPECT_GT(scale, 0.1);
    if (shading == sh::ShadingModel::phong) {
        EXPECT_TRUE(clamped) << "no negative shade to clamp: weak case";
    }
}

// The fused pass (its loops and the shader's structure-of-arrays input)
// computes what the separate passes do, on every SIMD target.
TEST(FrameShading, fused_frame_matches_the_separate_passes_on_every_target) {
    std::mt19937_64 rng(3);
    for (const std::string& target : simd_targets()) {
        force_simd_target(target);
        for (const sh::ShadingModel shading : {sh::ShadingModel::diffuse, sh::ShadingModel::phong,
                                               sh::ShadingModel::translucent})
            expect_fused_frame_matches_separate_passes(rng, shading, target);
    }
    force_simd_target("");
}

TEST(FrameShading, results_do_not_depend_on_thread_count) {
    std::mt19937_64 rng(4);
    FrameCase c = frame_case(rng, sh::ShadingModel::phong);
    const std::size_t V = c.polygons.vertex_count();
    const ShadingMesh mesh(V, c.polygons.sizes, c.polygons.loops);
    const sh::PoseShader shader(4);
    std::vector<float> first_rgba, first_ao;
    for (const int threads : {1, 2, 3}) {
        c.parameters.threads = threads;
        std::vector<float> rgba(4 * V), ao(V);
        shade_frame(c.model, shader, mesh, c.rotations.data(), c.polygons.positions.data(), c.world, c.lighting,
                    c.parameters, rgba.data(), ao.data());
        if (first_rgba.empty()) first_rgba = rgba, first_ao = ao;
        EXPECT_EQ(rgba, first_rgba) << threads;
        EXPECT_EQ(ao, first_ao) << threads;
    }
}

TEST(FrameShading, mismatches_are_argument_errors_before_anything_is_written) {
    std::mt19937_64 rng(5);
    FrameCase c = frame_case(rng, sh::ShadingModel::diffuse);
    const std::size_t V = c.polygons.vertex_count();
    const ShadingMesh mesh(V, c.polygons.sizes, c.polygons.loops);
    const ShadingMesh other(V + 1, c.polygons.sizes, c.polygons.loops);
    std::vector<float> rgba(4 * V, -7.0f), ao(V, -7.0f);
    const auto shade = [&](const ShadingMesh& m, const sh::PoseShader& s) {
        return shade_frame(c.model, s, m, c.rotations.data(), c.polygons.positions.data(), c.world, c.lighting,
                           c.parameters, rgba.data(), ao.data());
    };
    EXPECT_THROW(shade(other, sh::PoseShader(4)), ArgumentError);
    EXPECT_THROW(shade(mesh, sh::PoseShader(3)), ArgumentError);
    c.rotations[4] = std::nanf("");
    EXPECT_THROW(shade(mesh, sh::PoseShader(4)), ArgumentError);
    c.rotations[4] = 1.0f;
    c.lighting(2, 1) = INFINITY;
    EXPECT_THROW(shade(mesh, sh::PoseShader(4)), ArgumentError);
    EXPECT_TRUE(std::all_of(rgba.begin(), rgba.end(), [](float x) { return x == -7.0f; }));
    EXPECT_TRUE(std::all_of(ao.begin(), ao.end(), [](float x) { return x == -7.0f; }));
}

// The shader turns the model's lobe parameters into axes itself
// (PoseBuffers::lobe_params): the same as zh_fit's lambert_to_axis, also
// for points beyond the disc and non-finite ones.
TEST(FrameShading, lobe_parameters_shade_like_the_axes_lambert_to_axis_gives) {
    std::mt19937_64 rng(6);
    std::uniform_real_distribution<double> uniform(-2.5, 2.5);
    const int order = 4, lobes = 2;
    const std::size_t n = 61;
    std::vector<double> params(n * lobes * (2 + order)), axes(n * lobes * 3), bands(n * lobes * order),
        normals(3 * n), tangents(3 * n), positions(3 * n);
    for (double& x : params) x = uniform(rng);
    params[0] = NAN;  // → +z
    for (std::size_t i = 0; i < n * lobes; ++i) {
        const Eigen::Vector3d a = lambert_to_axis(params[i * 6], params[i * 6 + 1]);
        for (int k = 0; k < 3; ++k) axes[3 * i + k] = a[k];
        for (int l = 0; l < order; ++l) bands[order * i + l] = params[i * 6 + 2 + l];
    }
    for (std::size_t v = 0; v < n; ++v) {
        const Eigen::Vector3d nv = Eigen::Vector3d(uniform(rng), uniform(rng), 1.0).normalized();
        const Eigen::Vector3d tv = nv.unitOrthogonal();
        for (int k = 0; k < 3; ++k) {
            normals[3 * v + k] = nv[k];
            tangents[3 * v + k] = tv[k];
            positions[3 * v + k] = uniform(rng);
        }
    }
    std::vector<double> rgb_axes(3 * n), rgb_params(3 * n), ao_axes(n), ao_params(n);
    sh::PoseBuffers<double> with_axes{n, lobes, axes.data(), bands.data(), normals.data(), tangents.data(),
                                      positions.data(), rgb_axes.data(), ao_axes.data()};
    sh::PoseBuffers<double> with_params{n, lobes, nullptr, nullptr, normals.data(), tangents.data(),
                                        positions.data(), rgb_params.data(), ao_params.data(), params.data()};
    sh::ShadingParameters p;
    p.model = sh::ShadingModel::phong;
    p.camera = Eigen::Vector3d(0, 0, 5);
    const Eigen::MatrixXd lighting = Eigen::MatrixXd::Random(16, 3);
    const sh::PoseShader shader(order);
    shader.shade(lighting, p, with_axes);
    shader.shade(lighting, p, with_params);
    for (std::size_t k = 0; k < 3 * n; ++k) EXPECT_NEAR(rgb_params[k], rgb_axes[k], 1e-12) << k;
    for (std::size_t k = 0; k < n; ++k) EXPECT_NEAR(ao_params[k], ao_axes[k], 1e-12) << k;
}

}  // namespace
}  // namespace penumbra::visibility
