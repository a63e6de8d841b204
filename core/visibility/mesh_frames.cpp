#include "visibility/mesh_frames.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>

#include <Eigen/Geometry>

#include "common/error.hpp"
#include "common/hash.hpp"
#include "common/parallel.hpp"

namespace penumbra::visibility {

namespace {

Eigen::Vector3d vec(const std::vector<float>& a, std::size_t i) {
    return Eigen::Vector3d(a[3 * i], a[3 * i + 1], a[3 * i + 2]);
}

void check_triangles(std::size_t vertex_count, const std::vector<std::uint32_t>& triangles) {
    if (triangles.size() % 3 != 0) throw ArgumentError("triangles must hold whole triples of vertex indices");
    for (std::uint32_t i : triangles)
        if (i >= vertex_count)
            throw ArgumentError("triangle index " + std::to_string(i) + " is out of range (" +
                                std::to_string(vertex_count) + " vertices)");
}

}  // namespace

std::vector<std::uint32_t> reference_neighbours(std::size_t vertex_count, const std::vector<std::uint32_t>& polygon_sizes,
                                                const std::vector<std::uint32_t>& polygon_vertices) {
    std::vector<std::uint32_t> sizes = polygon_sizes;
    if (sizes.empty()) {
        check_triangles(vertex_count, polygon_vertices);
        sizes.assign(polygon_vertices.size() / 3, 3u);
    }
    std::size_t total = 0;
    for (auto s : sizes) total += s;
    if (total != polygon_vertices.size())
        throw ArgumentError("polygon sizes add up to " + std::to_string(total) + " but " +
                            std::to_string(polygon_vertices.size()) + " polygon vertices were given");
    for (std::uint32_t i : polygon_vertices)
        if (i >= vertex_count)
            throw ArgumentError("polygon vertex index " + std::to_string(i) + " is out of range (" +
                                std::to_string(vertex_count) + " vertices)");
    std::vector<std::uint32_t> neighbour(vertex_count);
    std::vector<bool> seen(vertex_count, false);
    for (std::size_t v = 0; v < vertex_count; ++v) neighbour[v] = static_cast<std::uint32_t>(v);
    std::size_t start = 0;
    for (auto size : sizes) {
        for (std::uint32_t k = 0; k < size; ++k) {
            const std::uint32_t v = polygon_vertices[start + k], next = polygon_vertices[start + (k + 1) % size];
            if (!seen[v] && next != v) {
                neighbour[v] = next;
                seen[v] = true;
            }
        }
        start += size;
    }
    return neighbour;
}

void basis_from_normal(const Eigen::Vector3d& n, Eigen::Vector3d& t, Eigen::Vector3d& b) {
    const double sign = std::copysign(1.0, n.z());
    const double a = -1.0 / (sign + n.z());
    const double c = n.x() * n.y() * a;
    t = Eigen::Vector3d(1.0 + sign * n.x() * n.x() * a, sign * c, -sign * n.x());
    b = Eigen::Vector3d(c, sign + n.y() * n.y() * a, -n.y());
}

bool vertex_frame(const Eigen::Vector3d& n, const Eigen::Vector3d& edge_vector, bool has_neighbour, float* out) {
    Eigen::Vector3d t = edge_vector - n * n.dot(edge_vector);
    Eigen::Vector3d b;
    const double length = t.norm();
    // An edge within ~0.06° of the normal gives no usable direction.
    const bool from_edge = has_neighbour && length > 1e-3 * edge_vector.norm() && std::isfinite(length);
    if (from_edge) {
        t /= length;
        b = n.cross(t);
    } else {
        basis_from_normal(n, t, b);
    }
    for (int k = 0; k < 3; ++k) {
        out[k] = float(t[k]);
        out[3 + k] = float(b[k]);
        out[6 + k] = float(n[k]);
    }
    return from_edge;
}

void vertex_frames(const std::vector<float>& positions, const std::vector<float>& normals,
                   const std::vector<std::uint32_t>& triangles, const std::vector<std::uint32_t>& neighbours,
                   float* frames_out, FrameStats* stats, int threads) {
    const std::size_t n_vertices = positions.size() / 3;
    if (positions.size() % 3 != 0 || normals.size() != positions.size())
        throw ArgumentError("positions and normals must both be (V, 3) with the same V");
    if (neighbours.size() != n_vertices) throw ArgumentError("one reference neighbour per vertex is needed");
    check_triangles(n_vertices, triangles);
    FrameStats local;
    // One vertex's frame from its unit normal n; false when t fell back to
    // the frame of n alone.
    const auto write_frame = [&](std::size_t v, const Eigen::Vector3d& n) {
        return vertex_frame(n, vec(positions, neighbours[v]) - vec(positions, v), neighbours[v] != v,
                            frames_out + 9 * v);
    };
    // Every vertex whose normal Blender reports usable, in parallel (one pass,
    // no copy of the normals); the rest are repaired below.
    std::atomic<std::size_t> fallback{0};
    std::vector<std::uint8_t> broken(n_vertices, 0);
    parallel_for(n_vertices, {threads, 16384, "visibility.frames"}, [&](std::size_t begin, std::size_t end) {
        std::size_t fallbacks = 0;
        for (std::size_t v = begin; v < end; ++v) {
            const Eigen::Vector3d normal = vec(normals, v);
            const double length = normal.norm();
            if (!(length > 1e-20) || !std::isfinite(length)) {
                broken[v] = 1;
                continue;
            }
            fallbacks += write_frame(v, normal / length) ? 0 : 1;
        }
        fallback += fallbacks;
    });
    // Normals that Blender reports as zero (isolated or degenerate geometry):
    // the area-weighted normal of the vertex's triangles, or +z.
    std::size_t repaired = 0;
    for (const std::uint8_t b : broken) repaired += b;
    if (repaired) {
        std::vector<Eigen::Vector3d> area_normal(n_vertices, Eigen::Vector3d::Zero());
        for (std::size_t t = 0; t < triangles.size() / 3; ++t) {
            const auto a = vec(positions, triangles[3 * t]), b = vec(positions, triangles[3 * t + 1]),
                       c = vec(positions, triangles[3 * t + 2]);
            const Eigen::Vector3d face = (b - a).cross(c - a);
            if (!face.allFinite()) continue;
            for (int k = 0; k < 3; ++k) area_normal[triangles[3 * t + k]] += face;
        }
        for (std::size_t v = 0; v < n_vertices; ++v) {
            if (!broken[v]) continue;
            const double length = area_normal[v].norm();
            const Eigen::Vector3d n = length > 0.0 && std::isfinite(length) ? Eigen::Vector3d(area_normal[v] / length)
                                                                             : Eigen::Vector3d::UnitZ();
            fallback += write_frame(v, n) ? 0 : 1;
        }
        local.repaired_normals = repaired;
    }
    local.fallback_tangents = fallback.load();
    if (stats) *stats = local;
}

MeshDiagnostics mesh_diagnostics(const std::vector<float>& positions, const std::vector<float>& normals,
                                 const std::vector<std::uint32_t>& triangles) {
    const std::size_t n_vertices = positions.size() / 3;
    if (positions.size() % 3 != 0 || normals.size() != positions.size())
        throw ArgumentError("positions and normals must both be (V, 3) with the same V");
    check_triangles(n_vertices, triangles);
    MeshDiagnostics d;
    if (n_vertices == 0) return d;
    Eigen::Vector3d lo = vec(positions, 0), hi = lo;
    for (std::size_t v = 1; v < n_vertices; ++v) {
        lo = lo.cwiseMin(vec(positions, v));
        hi = hi.cwiseMax(vec(positions, v));
    }
    d.bounding_diagonal = (hi - lo).norm();
    const Eigen::Vector3d centre = 0.5 * (lo + hi);
    std::vector<Eigen::Vector3d> winding(n_vertices, Eigen::Vector3d::Zero());
    double largest_area = 0.0;
    std::vector<double> areas(triangles.size() / 3);
    for (std::size_t t = 0; t < triangles.size() / 3; ++t) {
        const Eigen::Vector3d a = vec(positions, triangles[3 * t]) - centre,
                              b = vec(positions, triangles[3 * t + 1]) - centre,
                              c = vec(positions, triangles[3 * t + 2]) - centre;
        const Eigen::Vector3d face = (b - a).cross(c - a);
        areas[t] = 0.5 * face.norm();
        largest_area = std::max(largest_area, areas[t]);
        d.signed_volume += a.dot(b.cross(c)) / 6.0;
        for (int k = 0; k < 3; ++k) winding[triangles[3 * t + k]] += face;
    }
    for (double area : areas)
        if (!(area > 1e-12 * largest_area)) ++d.zero_area_triangles;
    std::size_t disagree = 0, judged = 0;
    for (std::size_t v = 0; v < n_vertices; ++v) {
        const Eigen::Vector3d n = vec(normals, v);
        if (!(n.norm() > 1e-20) || !n.allFinite()) {
            ++d.zero_length_normals;
            continue;
        }
        if (winding[v].norm() == 0.0) continue;
        ++judged;
        if (n.dot(winding[v]) < 0.0) ++disagree;
    }
    d.inward_normal_fraction = judged ? double(disagree) / judged : 0.0;
    const Eigen::Vector3d extent = hi - lo;
    const double box_volume = extent.x() * extent.y() * extent.z();
    d.normals_point_inward = (box_volume > 0.0 && d.signed_volume < -1e-3 * box_volume) ||
                             d.inward_normal_fraction > 0.5;
    return d;
}

std::uint64_t topology_hash(std::size_t vertex_count, const std::vector<std::uint32_t>& polygon_sizes,
                            const std::vector<std::uint32_t>& polygon_vertices) {
    std::uint64_t count = vertex_count;
    std::uint64_t hash = fnv1a64(&count, sizeof count);
    std::size_t total = 0;
    for (std::uint32_t s : polygon_sizes) total += s;
    if (total != polygon_vertices.size())
        throw ArgumentError("polygon sizes add up to " + std::to_string(total) + " but " +
                            std::to_string(polygon_vertices.size()) + " polygon vertices were given");
    std::size_t at = 0;
    for (std::uint32_t s : polygon_sizes) {
        hash = fnv1a64(&s, sizeof s, hash);
        hash = fnv1a64(polygon_vertices.data() + at, s * sizeof(std::uint32_t), hash);
        at += s;
    }
    return hash;
}

}  // namespace penumbra::visibility
