// Per-vertex visibility of a deforming mesh, one frame at a time (paper
// §3.1, fig. 2a): rays from each vertex over the whole sphere along a
// deterministic direction set, occluded or not, projected onto SH in the
// vertex's tangent frame (mesh_frames.hpp). Plain binary visibility, not
// cosine-weighted (paper §3.2), unless asked for (the comparison of fig. 3).
//
// The result of a bake is a TrainingSet: per frame, the visibility of every
// vertex and the pose (bone rotations) that produced it. Training sets of
// separate frame ranges can be baked in separate processes (a render farm),
// written with write_training_set and merged with merge_training_sets
// before the fit (pose_model.hpp).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/setting.hpp"
#include "common/progress.hpp"
#include "visibility/mesh_frames.hpp"
#include "visibility/occlusion_scene.hpp"
#include "visibility/order_limit.hpp"

namespace penumbra::visibility {

// What a ray aimed below the vertex's tangent plane counts as.
enum class BelowHorizon : std::uint32_t {
    Occluded = 0,  // not cast; counted as blocked (a closed skin blocks them: they cross the interior)
    Cast = 1,      // cast from just below the surface (thin open surfaces, membranes)
};

enum class Weighting : std::uint32_t {
    Plain = 0,   // V(ω): what the model fits (paper §3.2)
    Cosine = 1,  // V(ω)·max(0, cosθ)/π: the cosine-weighted transfer, for the fig. 3 comparison
};

struct BakeSettings {
    int order = 4;          // SH order (bands 0..order−1)
    int rays = 256;         // directions over the whole sphere (spherical Fibonacci)
    static constexpr Range<int> order_range{1, max_sh_order};
    static constexpr Range<int> rays_range{4, 65536};
    BelowHorizon below_horizon = BelowHorizon::Occluded;
    Weighting weighting = Weighting::Plain;
    double offset_scale = 1e-4;  // ray origins sit offset_scale × (bounding-box diagonal) off the surface
    int threads = 0;             // 0: every core
};

// One frame of the character (world space) and its occluders.
struct FrameGeometry {
    TriangleMesh mesh;
    std::vector<float> normals;              // V × 3, Blender's vertex normals
    std::vector<TriangleMesh> occluders;     // other objects that cast shadows on it
};

struct FrameBakeStats {
    std::size_t rays_cast = 0;       // rays actually traced
    std::size_t rays_counted = 0;    // rays that entered the projection (cast + below-horizon ones)
    FrameStats frames;               // repaired normals, fallback tangents
    // Seconds spent on: the ray set, tangent frames and checks; building (or
    // updating) the Embree scene; casting and projecting.
    double seconds_setup = 0.0, seconds_build = 0.0, seconds_cast = 0.0;
    bool scene_updated = false;      // the previous frame's Embree scene was updated, not built anew
};

// Throws ArgumentError for settings out of range.
void check_bake_settings(const BakeSettings& settings);

// Visibility SH of every vertex in its own frame: writes V × order² floats.
// `neighbours` from reference_neighbours(mesh). Reports progress between
// chunks of 64 vertices; throws Cancelled if asked.
void bake_frame(const FrameGeometry& geometry, const std::vector<std::uint32_t>& neighbours,
                const BakeSettings& settings, float* visibility_out, const Progress& progress = {},
                FrameBakeStats* stats = nullptr, double progress_from = 0.0, double progress_to = 1.0);

// Frame after frame of one mesh: keeps the ray set and the Embree scene
// between frames, so that a frame whose meshes have the structure of the
// previous one (same vertex and triangle arrays, positions aside) only
// updates the vertex buffers and recommits (SceneBuild decides rebuild or
// refit). Gives exactly the result of bake_frame. One bake at a time.
struct RaySet;
class FrameBaker {
public:
    explicit FrameBaker(const BakeSettings& settings, SceneBuild build = SceneBuild::Medium,
                        Traversal traversal = Traversal::Fast);
    ~FrameBaker();
    FrameBaker(const FrameBaker&) = delete;
    FrameBaker& operator=(const FrameBaker&) = delete;

    const BakeSettings& settings() const { return settings_; }
    SceneBuild scene_build() const { return build_; }
    Traversal traversal() const { return traversal_; }
    void set_threads(int threads);
    void bake(const FrameGeometry& geometry, const std::vector<std::uint32_t>& neighbours, float* visibility_out,
              const Progress& progress = {}, FrameBakeStats* stats = nullptr, double progress_from = 0.0,
              double progress_to = 1.0);

private:
    BakeSettings settings_;
    SceneBuild build_;
    Traversal traversal_;
    std::unique_ptr<RaySet> rays_;
    std::unique_ptr<OcclusionScene> scene_;
};

// The direction set of a bake in the local frame (+z = normal) with its SH
// projection weights: row i of `projection` (order² values) is what a
// visible ray i adds to the vertex's SH vector.
struct RaySet {
    std::vector<Eigen::Vector3f> directions;
    std::vector<float> projection;  // rays × order²
    int upper = 0;                  // directions [0, upper) have z >= 0
};
RaySet make_ray_set(const BakeSettings& settings);

// One training frame: its scene frame number, the pose and the visibility.
struct TrainingFrame {
    double frame = 0.0;
    std::vector<float> bone_rotations;  // bones × 9: each bone's rotation relative to rest, row-major 3×3
    std::vector<float> visibility;      // vertices × order²
};

struct TrainingSet {
    BakeSettings settings;                 // order, rays, below_horizon, weighting (threads not stored)
    std::uint64_t vertex_count = 0;
    std::uint64_t topology_hash = 0;       // mesh_frames.hpp topology_hash
    std::vector<std::string> bone_names;   // every bone of the armature, in the order of bone_rotations
    std::vector<TrainingFrame> frames;     // sorted by frame number
};

// Checks sizes (every frame has bones × 9 rotations and vertices × order²
// visibility values, all finite); ArgumentError naming what is wrong.
void check_training_set(const TrainingSet& set);

// Pieces of one bake (same mesh, armature and settings) into one set, frames
// sorted; a frame present in two pieces is kept once (the first). Pieces that
// do not match throw ArgumentError saying how.
TrainingSet merge_training_sets(const std::vector<TrainingSet>& pieces);

}  // namespace penumbra::visibility
