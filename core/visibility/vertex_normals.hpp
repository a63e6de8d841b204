// Vertex normals of a deformed mesh by Blender's own rule, computed from the
// posed positions and the fixed polygons, so the run time need not ask
// Blender for them: reading a posed mesh's normals makes Blender compute
// them, which cost more CPU time than its whole frame change at 100k vertices
// (docs/visibility.md, "In Blender").
//
// The rule of Blender 4.x and 5.x (blenkernel mesh_normals.cc,
// normals_calc_faces and normals_calc_verts), in float and in Blender's
// order of operations, so the normals come out bit-identical
// (tests/blender/visibility/test_visibility.py compares them):
//  - face normal: Newell's method over the polygon's corners (any size),
//    normalized by multiplying with 1/length; a zero one becomes +z;
//  - vertex normal: over the vertex's faces in ascending order, the sum of
//    face normal × corner angle, the angle between the two edges leaving the
//    vertex taken as safe_acos_approx(dir_prev · dir_next) (a polynomial arc
//    cosine, max error 4.5e-5 rad), then normalized by dividing by the
//    length (a zero sum stays zero); a vertex that no face uses gets its
//    normalized position.
// Blender 3.4 weights the same way with the exact arc cosine, takes a quad's
// normal from its diagonals and sums the faces in no fixed order; its
// normals differ from these by float rounding and the arc cosine's error
// (measured there by the same test).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "visibility/vertex_kernels.hpp"

namespace penumbra::visibility {

class PolygonMesh {
public:
    // Polygons as Blender stores them: sizes and the concatenated vertex
    // loops (polygons of fewer than 3 corners are rejected). ArgumentError
    // for indices out of range or sizes that do not add up.
    PolygonMesh(std::size_t vertex_count, const std::vector<std::uint32_t>& polygon_sizes,
                const std::vector<std::uint32_t>& polygon_vertices);

    std::size_t vertex_count() const { return vertex_start_.size() - 1; }
    std::size_t face_count() const { return face_start_.size() - 1; }
    std::size_t corner_count() const { return corner_vertex_.size(); }

    // Normals (V × 3, unit or zero) of the mesh at `positions` (V × 3, the
    // space the normals are wanted in; Blender's are object space).
    // threads: 0 = all cores; the result does not depend on it.
    void vertex_normals(const float* positions, float* normals_out, int threads = 0) const;

    // The two passes of vertex_normals, for callers that fuse the second
    // with their own per-vertex work: every face's unit normal (F × 3, in an
    // array of 3F + 1 floats: the per-vertex pass reads four at a time) and
    // every corner's angle (C), then the normals of vertices [begin, end)
    // from them (row v − begin of normals_out).
    void face_pass(const float* positions, float* face_normals, float* corner_angles, int threads = 0) const;
    void vertex_normals_of(std::size_t begin, std::size_t end, const float* positions, const float* face_normals,
                           const float* corner_angles, float* normals_out) const;
    // The per-vertex half for callers with their own loops
    // (vertex_kernels.hpp): this mesh's incidences and the face pass's output.
    detail::NormalSources normal_sources(const float* face_normals, const float* corner_angles) const {
        return {vertex_start_.data(), incident_face_.data(), incident_corner_.data(), face_normals, corner_angles};
    }

private:
    std::vector<std::uint32_t> face_start_;     // F + 1 offsets into corner_vertex_
    std::vector<std::uint32_t> corner_vertex_;  // C
    // The faces by size, quads, then triangles, then the rest: the SIMD
    // loops take lanes of quads or of triangles.
    std::vector<std::uint32_t> faces_by_size_;
    std::size_t quad_count_ = 0, triangle_count_ = 0;
    // Per vertex, its faces in ascending order (Blender's vert_to_face_map)
    // and the corner whose angle weights each: the face's first corner at
    // this vertex, as face_find_adjacent_verts takes it.
    std::vector<std::uint32_t> vertex_start_;   // V + 1 offsets
    std::vector<std::uint32_t> incident_face_, incident_corner_;
};

}  // namespace penumbra::visibility
