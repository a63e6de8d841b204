// Embree occlusion queries over triangle meshes: the ray caster of the
// visibility baker. One scene per frame (the character as that frame deforms
// it, plus optional occluder objects), queried from many threads at once.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

namespace penumbra::visibility {

// A triangle soup in world space: positions (N × 3 floats, row-major) and
// triangles (M × 3 vertex indices).
struct TriangleMesh {
    std::vector<float> positions;
    std::vector<std::uint32_t> triangles;

    std::size_t vertex_count() const { return positions.size() / 3; }
    std::size_t triangle_count() const { return triangles.size() / 3; }
};

// How the scene's BVH is built. High: spatial splits (slowest build, fastest
// rays on a static scene); Medium: Embree's default; Low with the dynamic
// scene flag: fastest rebuild, meant for scenes rebuilt every frame; Refit:
// the first frame is built at Medium quality, later frames (update_positions)
// only refit its bounds (cheapest update, rays slow down as the pose moves
// away from the first frame). Measured in docs/visibility-benchmark.md.
enum class SceneBuild : std::uint32_t { High = 0, Medium = 1, Low = 2, Refit = 3 };

// Embree's arithmetic. Robust (RTC_SCENE_FLAG_ROBUST) makes the box tests
// conservative and the triangle test watertight, so that no ray slips
// between two triangles sharing an edge; Fast is Embree's default. Measured
// on the humanoid (48 frames × 9,914 vertices × 64 rays from just above the
// skin, docs/visibility.md): the same visibility bit for bit, cast about
// 20 % faster with Fast. A leak would turn one of a vertex's rays visible.
enum class Traversal : std::uint32_t { Fast = 0, Robust = 1 };

// A committed Embree scene on the process-wide device (created on first use
// and kept: creating a device starts Embree's threads, milliseconds each
// time). Thread-safe for queries once built.
// Triangles whose indices fall outside the vertex array, or with a
// non-finite vertex, throw penumbra::ArgumentError; zero-area triangles are
// kept (Embree never reports a hit on them).
class OcclusionScene {
public:
    explicit OcclusionScene(const std::vector<const TriangleMesh*>& meshes, SceneBuild build = SceneBuild::Medium,
                            Traversal traversal = Traversal::Fast);
    ~OcclusionScene();
    OcclusionScene(const OcclusionScene&) = delete;
    OcclusionScene& operator=(const OcclusionScene&) = delete;

    // A bundle of rays with a common origin. Writes occluded[i] = 1 when
    // something lies along origin + t·directions[i] for t in (t_near, t_far),
    // else 0. Directions need not be normalized. With use_packets, cast as
    // packets of the widest width the CPU runs natively (16, 8 or 4);
    // otherwise one by one (rtcOccluded1). The bake uses single rays: its
    // directions spread over a hemisphere, and packets measured slower
    // (docs/visibility-benchmark.md).
    void occluded_bundle(const Eigen::Vector3f& origin, const Eigen::Vector3f* directions, int count,
                         float t_near, float t_far, std::uint8_t* occluded, bool use_packets = false) const;

    // Rays each from its own origin (count <= width), cast as one packet of
    // `width` lanes (rtcOccluded16/8/4; 1: one by one; 0: packet_width()).
    // Writes occluded[i] like occluded_bundle. For coherent rays (nearby
    // origins, nearly parallel directions): the same ray of neighbouring
    // vertices, which bench/cpp/visibility_bake_bench.cpp casts this way.
    // The bake does not: on the humanoid it measured slower than single rays,
    // even with every lane given the same direction (docs/visibility.md).
    void occluded_packet(const Eigen::Vector3f* origins, const Eigen::Vector3f* directions, int count, float t_near,
                         float t_far, std::uint8_t* occluded, int width = 0) const;

    // The next frame of the same meshes: when their number, vertex counts and
    // triangles equal the scene's, copies the new positions into the
    // existing buffers and recommits (rebuild, or refit for SceneBuild::
    // Refit) and returns true; otherwise changes nothing and returns false.
    // Validates like the constructor. Not thread-safe with queries.
    bool update_positions(const std::vector<const TriangleMesh*>& meshes);

    // The packet width occluded_bundle uses with use_packets (16, 8, 4 or 1).
    int packet_width() const;

    // One ray at a time (rtcOccluded1): the baseline the benchmark compares
    // the packet path against.
    bool occluded1(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_near,
                   float t_far) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace penumbra::visibility
