// _penumbra.visibility: the visibility baker of core/visibility. This file
// holds its enums, the mesh helpers and the ZH lobes on their own; the
// training set (baking) and the pose model (fitting, shading) have a file
// each. numpy in and out; inputs are copied into C++ buffers before the GIL
// is released.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>
#include <vector>

#include "arrays.hpp"
#include "bindings.hpp"
#include "enums.hpp"
#include "visibility/mesh_frames.hpp"
#include "visibility/order_limit.hpp"
#include "visibility/pose_features.hpp"
#include "visibility/visibility_bake.hpp"
#include "visibility/zh_fit.hpp"
#include "visibility/zh_rows.hpp"

namespace py = pybind11;
namespace vis = penumbra::visibility;

namespace penumbra::bindings {

namespace {

void bind_enums(py::module_& m) {
    bind_enum<vis::BelowHorizon>(m, "BelowHorizon", "below_horizon",
        {{"OCCLUDED", vis::BelowHorizon::Occluded}, {"CAST", vis::BelowHorizon::Cast}},
        "What a ray aimed below a vertex's tangent plane counts as: OCCLUDED (not cast, blocked: closed skins) "
        "or CAST (traced from just below the surface: open, thin surfaces).");
    bind_enum<vis::Weighting>(m, "Weighting", "weighting",
        {{"PLAIN", vis::Weighting::Plain}, {"COSINE", vis::Weighting::Cosine}},
        "What is baked: PLAIN visibility V (what the model fits) or COSINE, V·max(0, cos θ)/π.");
    bind_enum<vis::PoseFeatures>(m, "PoseFeatures", "features",
        {{"MATRIX", vis::PoseFeatures::RotationMatrix}, {"ROTATION_VECTOR", vis::PoseFeatures::RotationVector}},
        "The features of a joint the pose model is linear in: MATRIX (R − I) or ROTATION_VECTOR.");
    bind_enum<vis::SceneBuild>(m, "SceneBuild", "scene_build",
        {{"HIGH", vis::SceneBuild::High}, {"MEDIUM", vis::SceneBuild::Medium}, {"LOW", vis::SceneBuild::Low},
         {"REFIT", vis::SceneBuild::Refit}},
        "How the Embree scene is built for each frame (Embree's build qualities; REFIT updates the previous "
        "frame's tree). Every choice bakes the same visibility; they differ in time.");
}

py::tuple vertex_frames(const Floats& positions, const Floats& normals, const Indices& triangles,
                        const Indices& neighbours) {
    const auto p = triples(positions, "positions"), n = triples(normals, "normals");
    const auto t = indices(triangles, "triangles", true), nb = indices(neighbours, "neighbours", false);
    std::vector<float> frames(3 * p.size());
    vis::FrameStats stats;
    {
        py::gil_scoped_release release;
        vis::vertex_frames(p, n, t, nb, frames.data(), &stats);
    }
    py::dict s;
    s["repaired_normals"] = stats.repaired_normals;
    s["fallback_tangents"] = stats.fallback_tangents;
    return py::make_tuple(to_array(frames, {py::ssize_t(p.size() / 3), 3, 3}), s);
}

py::dict mesh_diagnostics(const Floats& positions, const Floats& normals, const Indices& triangles) {
    const auto d = vis::mesh_diagnostics(triples(positions, "positions"), triples(normals, "normals"),
                                         indices(triangles, "triangles", true));
    py::dict out;
    out["bounding_diagonal"] = d.bounding_diagonal;
    out["signed_volume"] = d.signed_volume;
    out["inward_normal_fraction"] = d.inward_normal_fraction;
    out["zero_area_triangles"] = d.zero_area_triangles;
    out["zero_length_normals"] = d.zero_length_normals;
    out["normals_point_inward"] = d.normals_point_inward;
    return out;
}

void bind_mesh_helpers(py::module_& m) {
    m.def("reference_neighbours", [](std::size_t vertex_count, const Indices& polygon_sizes,
                                     const Indices& polygon_vertices) {
        const auto n = vis::reference_neighbours(vertex_count, indices(polygon_sizes, "polygon_sizes", false),
                                                 indices(polygon_vertices, "polygon_vertices", false));
        return to_array(n, {py::ssize_t(n.size())});
    }, py::arg("vertex_count"), py::arg("polygon_sizes"), py::arg("polygon_vertices"),
       "Reference neighbour of each vertex (the next vertex of the first polygon using it): fixes the tangent of "
       "its frame. Empty polygon_sizes: polygon_vertices are triangles.");

    m.def("vertex_frames", &vertex_frames, py::arg("positions"), py::arg("normals"), py::arg("triangles"),
          py::arg("neighbours"),
       "Tangent frames (V, 3, 3), rows t, b, n, and counts of repaired normals and fallback tangents.");

    m.def("mesh_diagnostics", &mesh_diagnostics, py::arg("positions"), py::arg("normals"), py::arg("triangles"),
       "Checks before a bake: bounding diagonal, signed volume, inward normals, degenerate faces and normals.");

    m.def("topology_hash", [](std::size_t vertex_count, const Indices& polygon_sizes,
                              const Indices& polygon_vertices) {
        return vis::topology_hash(vertex_count, indices(polygon_sizes, "polygon_sizes", false),
                                  indices(polygon_vertices, "polygon_vertices", false));
    }, py::arg("vertex_count"), py::arg("polygon_sizes"), py::arg("polygon_vertices"),
       "FNV-1a 64 fingerprint of the polygon topology, stored in model files.");
}

// The SH order of rows of order² values, or ValueError.
int order_of_rows(const Doubles& sh) {
    if (sh.ndim() != 2) throw py::value_error("sh must be (N, order²), got " + shape_of(sh));
    return order_of_coefficient_count(sh.shape(1), vis::max_sh_order, "sh rows");
}

py::tuple fit_zh_lobes(const Doubles& sh, int lobes, py::object reference, int iterations, double axis_prior) {
    vis::ZhFitSettings s;
    s.order = order_of_rows(sh);
    s.lobes = lobes;
    s.iterations = iterations;
    s.axis_prior = axis_prior;
    const int order = s.order, d = lobes * vis::params_per_lobe(order);
    const py::ssize_t N = sh.shape(0);
    std::vector<double> ref;
    if (!reference.is_none()) {
        Doubles r = reference.cast<Doubles>();
        if (r.size() != N * d) throw py::value_error("reference must be (N, lobes, 2 + order)");
        ref.assign(r.data(), r.data() + r.size());
    }
    std::vector<double> in(sh.data(), sh.data() + sh.size()), out(N * d), residual(N);
    {
        py::gil_scoped_release release;
        vis::fit_zh_lobes_rows(s, std::size_t(N), in.data(), ref.empty() ? nullptr : ref.data(), out.data(),
                               residual.data());
    }
    return py::make_tuple(to_array(out, {N, lobes, vis::params_per_lobe(order)}), to_array(residual, {N}));
}

py::array_t<double> zh_params_to_sh(const Doubles& params) {
    if (params.ndim() != 3) throw py::value_error("params must be (N, lobes, 2 + order), got " + shape_of(params));
    const int lobes = int(params.shape(1)), order = int(params.shape(2)) - 2;
    if (order < 1 || order > vis::max_sh_order || lobes < 1 || lobes > vis::max_lobes)
        throw py::value_error("params must be (N, lobes 1.." + std::to_string(vis::max_lobes) + ", 2 + order 1.." +
                              std::to_string(vis::max_sh_order) + ")");
    const py::ssize_t N = params.shape(0);
    std::vector<double> out(N * order * order);
    vis::lobes_to_sh_rows(order, lobes, std::size_t(N), params.data(), out.data());
    return to_array(out, {N, py::ssize_t(order) * order});
}

void bind_zh_lobes(py::module_& m) {
    const vis::ZhFitSettings zh;  // the core's defaults
    m.def("fit_zh_lobes", &fit_zh_lobes, py::arg("sh"), py::arg("lobes") = zh.lobes, py::arg("reference") = py::none(),
          py::arg("iterations") = zh.iterations, py::arg("axis_prior") = zh.axis_prior,
       "Fits ZH lobes to SH vectors (N, order²). Returns (params (N, lobes, 2 + order): Lambert (X, Y) then "
       "bands; squared residuals (N,)).");

    m.def("zh_params_to_sh", &zh_params_to_sh, py::arg("params"),
          "Paper Eq. 1 for lobe parameters (N, lobes, 2 + order): (N, order²) SH.");

    m.def("zh_lambert_to_axis", [](double X, double Y) {
        const Eigen::Vector3d a = vis::lambert_to_axis(X, Y);
        return py::make_tuple(a.x(), a.y(), a.z());
    }, py::arg("X"), py::arg("Y"), "Inverse of the seam-free lobe-axis map (Lambert azimuthal equal-area about +z).");

    m.def("ambient_occlusion", [](const Doubles& sh) {
        const int order = order_of_rows(sh);
        std::vector<double> out(sh.shape(0));
        vis::ambient_occlusion_rows(order, out.size(), sh.data(), out.data());
        return to_array(out, {sh.shape(0)});
    }, py::arg("sh"), "Cosine-weighted visibility (AO) √(4π)(T_diffuse v)_00 of SH visibility vectors.");
}

}  // namespace

void bind_visibility(py::module_& m) {
    m.attr("MAX_ORDER") = vis::max_sh_order;  // the tool's limit, not sh.MAX_ORDER (visibility/order_limit.hpp)
    m.attr("MAX_LOBES") = vis::max_lobes;
    bind_enums(m);
    bind_visibility_training(m);
    bind_visibility_model(m);
    bind_mesh_helpers(m);
    bind_zh_lobes(m);
}

}  // namespace penumbra::bindings
