// Blender's vertex normals (header: the rule). The topology is prepared
// here; the arithmetic is vertex_kernels.cpp's, which keeps Blender's float
// operations in Blender's order, uncontracted (-ffp-contract=off), so the
// results are bit-identical to 4.x/5.x on every SIMD target.
#include "visibility/vertex_normals.hpp"

#include <algorithm>
#include <string>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "visibility/vertex_kernels.hpp"

namespace penumbra::visibility {


PolygonMesh::PolygonMesh(std::size_t vertex_count, const std::vector<std::uint32_t>& polygon_sizes,
                         const std::vector<std::uint32_t>& polygon_vertices) {
    std::size_t total = 0;
    for (const std::uint32_t size : polygon_sizes) {
        if (size < 3) throw ArgumentError("a polygon needs at least 3 corners, got " + std::to_string(size));
        total += size;
    }
    if (total != polygon_vertices.size())
        throw ArgumentError("polygon sizes add up to " + std::to_string(total) + " but " +
                            std::to_string(polygon_vertices.size()) + " polygon vertices were given");
    if (total >= 0xffffffffu || vertex_count >= 0xffffffffu)
        throw ArgumentError("the mesh is too large (2^32 corners or vertices)");
    for (const std::uint32_t v : polygon_vertices)
        if (v >= vertex_count)
            throw ArgumentError("polygon vertex index " + std::to_string(v) + " is out of range (" +
                                std::to_string(vertex_count) + " vertices)");
    corner_vertex_ = polygon_vertices;
    face_start_.assign(1, 0);
    for (const std::uint32_t size : polygon_sizes) face_start_.push_back(face_start_.back() + size);
    for (const std::uint32_t size : {4u, 3u, 0u})
        for (std::size_t f = 0; f < polygon_sizes.size(); ++f)
            if (polygon_sizes[f] == size || (size == 0 && polygon_sizes[f] > 4)) faces_by_size_.push_back(std::uint32_t(f));
    for (const std::uint32_t size : polygon_sizes) {
        quad_count_ += size == 4;
        triangle_count_ += size == 3;
    }

    // Counting sort of the corners by vertex keeps each vertex's faces in
    // ascending order (corners are stored face by face).
    vertex_start_.assign(vertex_count + 1, 0);
    for (const std::uint32_t v : corner_vertex_) ++vertex_start_[v + 1];
    for (std::size_t v = 0; v < vertex_count; ++v) vertex_start_[v + 1] += vertex_start_[v];
    incident_face_.resize(total);
    incident_corner_.resize(total);
    std::vector<std::uint32_t> fill(vertex_start_.begin(), vertex_start_.end() - 1);
    for (std::size_t f = 0; f + 1 < face_start_.size(); ++f)
        for (std::uint32_t c = face_start_[f]; c < face_start_[f + 1]; ++c) {
            const std::uint32_t v = corner_vertex_[c];
            // A vertex used twice by one face weights both entries by its
            // first corner there (face_find_adjacent_verts).
            std::uint32_t first = face_start_[f];
            while (corner_vertex_[first] != v) ++first;
            incident_face_[fill[v]] = std::uint32_t(f);
            incident_corner_[fill[v]++] = first;
        }
}

void PolygonMesh::face_pass(const float* positions, float* face_normals, float* corner_angles, int threads) const {
    // The loops are visibility/vertex_kernels.cpp's, in SIMD lanes of quads
    // and of triangles; blocks of faces_by_size_ split at the class borders.
    const std::size_t borders[] = {0, quad_count_, quad_count_ + triangle_count_, faces_by_size_.size()};
    const int sizes[] = {4, 3, 0};
    parallel_for(faces_by_size_.size(), {threads, 4096, "visibility.face_normals"}, [&](std::size_t begin, std::size_t end) {
        for (int k = 0; k < 3; ++k) {
            const std::size_t from = std::max(begin, borders[k]), to = std::min(end, borders[k + 1]);
            if (from < to)
                detail::face_normals_range(face_start_.data(), corner_vertex_.data(), positions,
                                           faces_by_size_.data() + from, to - from, sizes[k], face_normals,
                                           corner_angles);
        }
    });
}

void PolygonMesh::vertex_normals_of(std::size_t begin, std::size_t end, const float* positions,
                                    const float* face_normals, const float* corner_angles, float* normals_out) const {
    detail::vertex_normals_range(normal_sources(face_normals, corner_angles), positions, begin, end, normals_out);
}

void PolygonMesh::vertex_normals(const float* positions, float* normals_out, int threads) const {
    std::vector<float> face_normals(3 * face_count() + 1), corner_angles(corner_count());  // + 1: NormalSources
    face_pass(positions, face_normals.data(), corner_angles.data(), threads);
    parallel_for(vertex_count(), {threads, 8192, "visibility.vertex_normals"}, [&](std::size_t begin, std::size_t end) {
        vertex_normals_of(begin, end, positions, face_normals.data(), corner_angles.data(), normals_out + 3 * begin);
    });
}

}  // namespace penumbra::visibility
