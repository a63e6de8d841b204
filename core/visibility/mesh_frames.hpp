// Per-vertex tangent frames (t, b, n), z = n, in which the baker stores
// visibility and the run time shades; plus the checks a mesh must pass before
// it is baked (inward normals, degenerate faces) and the topology fingerprint
// that ties a model file to its mesh.
//
// Frame convention: n is the vertex normal Blender reports; t is the
// direction from the vertex to its reference neighbour (the next vertex, in
// winding order, of the first polygon that uses the vertex), projected onto
// the tangent plane; b = n × t. Because t follows an edge of the mesh, the
// frame turns with the skin as it deforms, so the visibility seen in it
// changes smoothly with pose. Where that edge is (nearly) parallel to n, t
// falls back to the frame of Duff et al. 2017 built from n alone.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "common/hash.hpp"

namespace penumbra::visibility {

// Reference neighbour of each vertex from the polygons (sizes and the
// concatenated vertex loops, as Blender stores them; empty sizes: the
// vertices are triangles). Polygons, not triangles, because Blender may split
// a bent quad along the other diagonal. A vertex that no polygon uses gets
// its own index (its frame then uses the fallback). Indices out of range
// throw penumbra::ArgumentError.
std::vector<std::uint32_t> reference_neighbours(std::size_t vertex_count, const std::vector<std::uint32_t>& polygon_sizes,
                                                const std::vector<std::uint32_t>& polygon_vertices);

struct FrameStats {
    std::size_t repaired_normals = 0;   // zero-length or non-finite normals replaced (see vertex_frames)
    std::size_t fallback_tangents = 0;  // tangents from the normal alone
};

// Frames for V vertices: positions and normals are V × 3 (normals need not be
// unit). Output: 9 floats per vertex, rows t, b, n (row-major local→world
// transposed: world = t·x + b·y + n·z). A zero-length or non-finite normal is
// replaced by the area-weighted normal of the vertex's triangles, and if that
// is zero too, by +z; such vertices are counted.
// threads: worker threads for the per-vertex pass (0: every core); the result
// does not depend on it.
void vertex_frames(const std::vector<float>& positions, const std::vector<float>& normals,
                   const std::vector<std::uint32_t>& triangles, const std::vector<std::uint32_t>& neighbours,
                   float* frames_out, FrameStats* stats = nullptr, int threads = 1);

// One vertex's frame (what vertex_frames writes for it) from its unit normal
// n and the vector to its reference neighbour (has_neighbour false: the
// vertex is its own); false when t fell back to the frame of n alone.
bool vertex_frame(const Eigen::Vector3d& n, const Eigen::Vector3d& edge_vector, bool has_neighbour, float* out);

// Duff et al. 2017, "Building an Orthonormal Basis, Revisited": t, b from n.
void basis_from_normal(const Eigen::Vector3d& n, Eigen::Vector3d& t, Eigen::Vector3d& b);

struct MeshDiagnostics {
    double bounding_diagonal = 0.0;    // of the positions
    double signed_volume = 0.0;        // Σ p0·(p1×p2)/6: > 0 for a closed mesh whose faces point out
    double inward_normal_fraction = 0.0;  // share of vertices whose normal points opposite the face winding
    std::size_t zero_area_triangles = 0;
    std::size_t zero_length_normals = 0;
    bool normals_point_inward = false; // the verdict, see mesh_diagnostics
};

// normals_point_inward is true when the mesh encloses volume with faces wound
// inward (signed volume < −1e-3 of its bounding box volume), or when most
// vertex normals disagree with their faces' winding.
MeshDiagnostics mesh_diagnostics(const std::vector<float>& positions, const std::vector<float>& normals,
                                 const std::vector<std::uint32_t>& triangles);

// FNV-1a 64 (common/hash.hpp) fingerprint of a mesh's topology: vertex count, then each
// polygon's size and vertex indices (Blender's polygons, not its triangles,
// whose split of a quad can change as the quad bends).
std::uint64_t topology_hash(std::size_t vertex_count, const std::vector<std::uint32_t>& polygon_sizes,
                            const std::vector<std::uint32_t>& polygon_vertices);

}  // namespace penumbra::visibility
