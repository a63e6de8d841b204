// _penumbra.visibility.PoseModel and fit_model: the linear pose-space ZH
// visibility model (core/visibility/pose_model.hpp), its file, and its run
// time (pose -> lobes -> shading, core/visibility/frame_shading.hpp).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <array>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "arrays.hpp"
#include "bindings.hpp"
#include "common/error.hpp"
#include "progress.hpp"
#include "sh/pose_shading.hpp"
#include "visibility/model_file.hpp"
#include "visibility/model_statistics.hpp"
#include "visibility/order_limit.hpp"
#include "visibility/pose_fit.hpp"
#include "visibility/pose_model.hpp"
#include "visibility/frame_shading.hpp"

namespace py = pybind11;
namespace vis = penumbra::visibility;

namespace penumbra::bindings {

namespace {

using Model = std::shared_ptr<vis::PoseModel>;

py::dict errors_dict(const vis::Errors& e) {
    py::dict d;
    d["sh_rms"] = e.sh_rms;
    d["ao_mean_abs"] = e.ao_mean_abs;
    d["ao_max_abs"] = e.ao_max_abs;
    d["samples"] = e.samples;
    return d;
}

// One PoseShader per SH order for the whole process: building one costs
// microseconds at order 4 and ~0.2 ms at order 8, and it caches the Phong
// operators of the exponents it has seen. PoseShader::shade is thread-safe,
// so the shared instance may serve concurrent calls. Taken with the GIL
// released: the mutex is only held to look up or build the shader, never
// while Python runs.
std::shared_ptr<const sh::PoseShader> shader_for(int order) {
    static std::mutex mutex;
    static std::array<std::shared_ptr<const sh::PoseShader>, vis::max_sh_order + 1> shaders;
    if (order < 1 || order > vis::max_sh_order)
        throw penumbra::ArgumentError("SH order must be in [1, " + std::to_string(vis::max_sh_order) + "]");
    std::lock_guard<std::mutex> lock(mutex);
    auto& slot = shaders[std::size_t(order)];
    if (!slot) slot = std::make_shared<const sh::PoseShader>(order);
    return slot;
}

// The lighting's SH coefficients, one row per term of `order`, RGB columns.
Eigen::MatrixXd lighting_sh(const Doubles& lighting, int order) {
    const py::ssize_t n_sh = py::ssize_t(order) * order;
    if (lighting.ndim() != 2 || lighting.shape(0) != n_sh || lighting.shape(1) != 3)
        throw py::value_error("lighting must have shape (" + std::to_string(n_sh) + ", 3), got " + shape_of(lighting));
    return array_to_matrix(lighting, "lighting");
}

sh::ShadingParameters shading_parameters(sh::ShadingModel model, double phong_exponent,
                                         const std::array<double, 3>& camera,
                                         const std::array<double, 3>& transmission, int threads) {
    sh::ShadingParameters sp;
    sp.model = model;
    sp.phong_exponent = phong_exponent;
    sp.camera = Eigen::Vector3d(camera[0], camera[1], camera[2]);
    sp.transmission = transmission;
    sp.threads = threads;
    return sp;
}

py::tuple synthesize(const vis::PoseModel& x, const Floats& joint_rotations, int threads) {
    const auto r = rotations(joint_rotations, x.joints.size(), "joint_rotations");
    const std::size_t V = x.vertex_count;
    std::vector<float> params(V * x.params_per_vertex()), axes(V * x.lobes * 3), bands(V * x.lobes * x.order);
    {
        py::gil_scoped_release release;
        vis::synthesize_lobes(x, r.data(), params.data(), axes.data(), bands.data(), threads);
    }
    return py::make_tuple(to_array(axes, {py::ssize_t(V), x.lobes, 3}),
                          to_array(bands, {py::ssize_t(V), x.lobes, x.order}),
                          to_array(params, {py::ssize_t(V), x.lobes, vis::params_per_lobe(x.order)}));
}

py::tuple shade(const vis::PoseModel& x, const Floats& joint_rotations, const Floats& positions,
                const Floats& normals, const Indices& triangles, const Indices& neighbours, const Doubles& lighting,
                sh::ShadingModel model, double phong_exponent, const std::array<double, 3>& camera,
                const std::array<double, 3>& transmission, int threads) {
    const auto r = rotations(joint_rotations, x.joints.size(), "joint_rotations");
    const auto p = triples(positions, "positions"), n = triples(normals, "normals");
    const auto t = indices(triangles, "triangles", true), nb = indices(neighbours, "neighbours", false);
    const Eigen::MatrixXd l = lighting_sh(lighting, x.order);
    const sh::ShadingParameters sp = shading_parameters(model, phong_exponent, camera, transmission, threads);
    vis::ShadingResult result;
    {
        py::gil_scoped_release release;
        const auto shader = shader_for(x.order);
        result = vis::shade_pose_model(x, *shader, r.data(), p, n, t, nb, l, sp);
    }
    py::dict info;
    info["seconds_pose_to_lobes"] = result.timings.pose_to_lobes;
    info["seconds_frames"] = result.timings.frames;
    info["seconds_shading"] = result.timings.shading;
    info["invalid_vertices"] = result.stats.invalid_vertices;
    info["repaired_normals"] = result.frame_stats.repaired_normals;
    return py::make_tuple(to_array(result.rgb, {py::ssize_t(x.vertex_count), 3}),
                          to_array(result.visibility, {py::ssize_t(x.vertex_count)}), info);
}

// A float32 array the caller lends for output: C-contiguous, writeable,
// exactly `shape`; None: a new one.
py::array_t<float> output_array(const py::object& given, const std::vector<py::ssize_t>& shape, const char* what) {
    if (given.is_none()) return py::array_t<float>(shape);
    const auto array = py::array::ensure(given);
    bool fits = array && array.dtype().is(py::dtype::of<float>()) && (array.flags() & py::array::c_style) &&
                array.writeable() && array.ndim() == py::ssize_t(shape.size());
    for (std::size_t k = 0; fits && k < shape.size(); ++k) fits = array.shape(py::ssize_t(k)) == shape[k];
    if (!fits) {
        std::string wanted;
        for (const auto n : shape) wanted += (wanted.empty() ? "" : ", ") + std::to_string(n);
        throw py::value_error(std::string(what) + " must be a writeable C-contiguous float32 array of shape (" +
                              wanted + (shape.size() == 1 ? ",)" : ")") + ", got " +
                              (array ? shape_of(array) + " " + std::string(py::str(array.dtype())) : "another type"));
    }
    return py::reinterpret_borrow<py::array_t<float>>(array);
}

// The evaluated mesh's (V, 3) float32 positions without a copy when they
// already are float32 and C-ordered (Floats converts anything else once).
const float* positions_of(const Floats& positions, std::size_t V) {
    const bool fits = (positions.ndim() == 2 && positions.shape(0) == py::ssize_t(V) && positions.shape(1) == 3) ||
                      (positions.ndim() == 1 && positions.shape(0) == py::ssize_t(3 * V));
    if (!fits)
        throw py::value_error("positions must be (" + std::to_string(V) + ", 3), got " + shape_of(positions));
    return positions.data();
}

py::tuple shade_frame(const vis::PoseModel& x, const vis::ShadingMesh& mesh, const Floats& joint_rotations,
                      const Floats& positions, const Doubles& world, const Doubles& lighting, sh::ShadingModel model,
                      double phong_exponent, const std::array<double, 3>& camera,
                      const std::array<double, 3>& transmission, int threads, const py::object& rgba_out,
                      const py::object& visibility_out) {
    const auto r = rotations(joint_rotations, x.joints.size(), "joint_rotations");
    const std::size_t V = x.vertex_count;
    const float* p = positions_of(positions, V);
    const Eigen::Matrix4d w = matrix4(world, "world");
    const Eigen::MatrixXd l = lighting_sh(lighting, x.order);
    const sh::ShadingParameters sp = shading_parameters(model, phong_exponent, camera, transmission, threads);
    auto rgba = output_array(rgba_out, {py::ssize_t(V), 4}, "rgba_out");
    auto visibility = output_array(visibility_out, {py::ssize_t(V)}, "visibility_out");
    float* rgba_data = rgba.mutable_data();
    float* visibility_data = visibility.mutable_data();
    vis::FrameResult result;
    {
        py::gil_scoped_release release;
        const auto shader = shader_for(x.order);
        result = vis::shade_frame(x, *shader, mesh, r.data(), p, w, l, sp, rgba_data, visibility_data);
    }
    py::dict info;
    info["seconds_normals"] = result.timings.normals;
    info["seconds_pose_to_lobes"] = result.timings.pose_to_lobes;
    info["seconds_frames"] = result.timings.frames;
    info["seconds_shading"] = result.timings.shading;
    info["invalid_vertices"] = result.stats.invalid_vertices;
    info["repaired_normals"] = result.frame_stats.repaired_normals;
    return py::make_tuple(rgba, visibility, info);
}

void bind_shading_mesh(py::module_& m) {
    auto mesh = py::class_<vis::ShadingMesh, std::shared_ptr<vis::ShadingMesh>>(m, "ShadingMesh",
        "What the frame shading keeps of a mesh between frames: its polygons (for Blender's vertex normals) and the "
        "reference neighbours of the bake's frames. Also bound as RuntimeMesh, its earlier name (the same class).");
    mesh
        .def(py::init([](std::size_t vertex_count, const Indices& polygon_sizes, const Indices& polygon_vertices) {
            return std::make_shared<vis::ShadingMesh>(vertex_count, indices(polygon_sizes, "polygon_sizes", false),
                                                      indices(polygon_vertices, "polygon_vertices", false));
        }), py::arg("vertex_count"), py::arg("polygon_sizes"), py::arg("polygon_vertices"))
        .def_property_readonly("vertex_count", [](const vis::ShadingMesh& x) { return x.polygons.vertex_count(); })
        .def("vertex_normals", [](const vis::ShadingMesh& x, const Floats& positions, int threads) {
            const float* p = positions_of(positions, x.polygons.vertex_count());
            py::array_t<float> out({py::ssize_t(x.polygons.vertex_count()), py::ssize_t(3)});
            float* o = out.mutable_data();
            {
                py::gil_scoped_release release;
                x.polygons.vertex_normals(p, o, threads);
            }
            return out;
        }, py::arg("positions"), py::arg("threads") = 0,
           "Vertex normals (V, 3) float32 of the mesh at `positions` by Blender 4.x/5.x's rule "
           "(core/visibility/vertex_normals.hpp): bit-identical to Blender's own there.");
    m.attr("RuntimeMesh") = mesh;  // the old name, kept for scripts written against it
}

void bind_properties(py::class_<vis::PoseModel, Model>& c) {
    c.def_property_readonly("order", [](const vis::PoseModel& x) { return x.order; })
        .def_property_readonly("lobes", [](const vis::PoseModel& x) { return x.lobes; })
        .def_property_readonly("rays", [](const vis::PoseModel& x) { return x.rays; })
        .def_property_readonly("below_horizon", [](const vis::PoseModel& x) { return x.below_horizon; })
        .def_property_readonly("features", [](const vis::PoseModel& x) { return x.features; })
        .def_property_readonly("vertex_count", [](const vis::PoseModel& x) { return x.vertex_count; })
        .def_property_readonly("topology_hash", [](const vis::PoseModel& x) { return x.topology_hash; })
        .def_property_readonly("joints", [](const vis::PoseModel& x) { return x.joints; })
        .def_property_readonly("armature_bones", [](const vis::PoseModel& x) { return x.armature_bones; })
        .def_property_readonly("summary", [](const vis::PoseModel& x) {
            py::dict d;
            for (const auto& [k, v] : x.summary) d[py::str(k)] = v;
            return d;
        })
        .def_property_readonly("constant_vertices", &vis::constant_vertex_count)
        .def("joints_per_vertex", [](const vis::PoseModel& x) {
            const std::vector<std::uint32_t> n = vis::joints_per_vertex(x);
            return to_array(n, {py::ssize_t(n.size())});
        });
}

// What the GPU preview uploads once per model (addon/penumbra/visibility/
// gpu_model.py): the stored arrays as they are, binary16 bits included, so the
// shader applies exactly the weights the CPU applies.
void bind_stored_blocks(py::class_<vis::PoseModel, Model>& c) {
    c.def("stored_blocks", [](const vis::PoseModel& x) {
        py::dict d;
        d["feature_offsets"] = to_array(x.feature_offsets, {py::ssize_t(x.feature_offsets.size())});
        d["joint_offsets"] = to_array(x.joint_offsets, {py::ssize_t(x.joint_offsets.size())});
        d["joint_index"] = to_array(x.joint_index, {py::ssize_t(x.joint_index.size())});
        d["block_directions"] = to_array(x.block_directions, {py::ssize_t(x.block_directions.size())});
        d["weight_scales"] = to_array(x.weight_scales, {py::ssize_t(x.weight_scales.size())});
        d["weight_offsets"] = to_array(x.weight_offsets, {py::ssize_t(x.weight_offsets.size())});
        d["weights"] = to_array(x.weights, {py::ssize_t(x.weights.size())});
        d["bias"] = to_array(x.bias, {py::ssize_t(x.vertex_count), py::ssize_t(x.params_per_vertex())});
        return d;
    }, "The stored per-vertex model (pose_model.hpp), for upload: feature_offsets (J + 1), joint_offsets (V + 1), "
       "joint_index, block_directions, weight_scales (one per block), weight_offsets (V + 1), weights (binary16 "
       "bits, uint16), bias (V, d).");
    c.def("pose_features", [](const vis::PoseModel& x, const Floats& joint_rotations) {
        const auto r = rotations(joint_rotations, x.joints.size(), "joint_rotations");
        const std::vector<float> f = vis::pose_features(x, r.data());
        return to_array(f, {py::ssize_t(f.size())});
    }, py::arg("joint_rotations"),
       "The pose vector of §4.3 step 1 (without its bias): each joint's features projected on its directions, "
       "joint after joint (float32, feature_offsets[-1] of them).");
    c.def_static("from_blocks", [](int order, int lobes, const std::vector<std::string>& joints,
                                   const Indices& feature_offsets, const Floats& feature_basis,
                                   const Indices& joint_offsets, const Indices& joint_index,
                                   const Indices& block_directions, const Floats& bias, const Floats& weights,
                                   std::uint64_t topology_hash) {
        auto model = std::make_shared<vis::PoseModel>();
        model->order = order;
        model->lobes = lobes;
        model->joints = joints;
        model->armature_bones = joints;
        model->topology_hash = topology_hash;
        const auto jo = indices(joint_offsets, "joint_offsets", false);
        if (jo.empty()) throw py::value_error("joint_offsets needs vertex_count + 1 entries");
        model->vertex_count = jo.size() - 1;
        model->joint_offsets = jo;
        model->feature_offsets = indices(feature_offsets, "feature_offsets", false);
        model->feature_basis.assign(feature_basis.data(), feature_basis.data() + feature_basis.size());
        for (auto j : indices(joint_index, "joint_index", false)) model->joint_index.push_back(std::uint16_t(j));
        for (auto c : indices(block_directions, "block_directions", false)) model->block_directions.push_back(std::uint8_t(c));
        model->bias.assign(bias.data(), bias.data() + bias.size());
        set_weights(*model, std::vector<float>(weights.data(), weights.data() + weights.size()));
        vis::check_pose_model(*model);
        return model;
    }, py::arg("order"), py::arg("lobes"), py::arg("joints"), py::arg("feature_offsets"), py::arg("feature_basis"),
       py::arg("joint_offsets"), py::arg("joint_index"), py::arg("block_directions"), py::arg("bias"),
       py::arg("weights"), py::arg("topology_hash") = 0,
       "A model from given weights (float, stored as binary16 blocks) in the stored layout, RotationMatrix "
       "features: synthetic models for tests and benchmarks. Raises ArgumentError when inconsistent.");
}

void bind_pose_model(py::module_& m) {
    const vis::BakeSettings bake;            // every default below is the core's own
    const sh::ShadingParameters shading;
    py::class_<vis::PoseModel, Model> c(m, "PoseModel",
        "The linear pose-space ZH visibility model of one mesh and armature.");
    c.def_static("load", [](const std::string& path) {
        py::gil_scoped_release release;
        return std::make_shared<vis::PoseModel>(vis::read_pose_model(path));
    }, py::arg("path"), "Reads a .pzh file; a missing, truncated or corrupted file raises IoError.")
        .def("save", [](const vis::PoseModel& model, const std::string& path) {
            py::gil_scoped_release release;
            vis::write_pose_model(path, model);
        }, py::arg("path"), "Writes the model atomically.");
    bind_properties(c);
    bind_stored_blocks(c);
    c.def("synthesize", &synthesize, py::arg("joint_rotations"), py::arg("threads") = bake.threads,
          "Paper §4.3 step 1: lobes for a pose. joint_rotations (J, 3, 3) in `joints` order. Returns "
          "(axes (V, c, 3) local, bands (V, c, order), params (V, c, 2 + order)).");
    c.def("evaluate", [](const vis::PoseModel& x, const vis::TrainingSet& s, int threads) {
        vis::Errors e;
        {
            py::gil_scoped_release release;
            e = vis::evaluate_pose_model(x, s, threads);
        }
        return errors_dict(e);
    }, py::arg("frames"), py::arg("threads") = bake.threads,
       "Errors of the model against baked frames (poses it may never have seen).");
    c.def("shade", &shade, py::arg("joint_rotations"), py::arg("positions"), py::arg("normals"), py::arg("triangles"),
          py::arg("neighbours"), py::arg("lighting"), py::arg("model") = shading.model,
          py::arg("phong_exponent") = shading.phong_exponent,
          py::arg("camera") = std::array<double, 3>{shading.camera[0], shading.camera[1], shading.camera[2]},
          py::arg("transmission") = shading.transmission, py::arg("threads") = bake.threads,
          "The whole run time for one pose: lobes from the pose, frames from the deformed mesh, shading with the SH "
          "engine under lighting (order², 3) with `model` (sh.ShadingModel, or its name). Returns (rgb (V, 3) "
          "float32, ao (V,) float32, info with timings).");
    c.def("shade_frame", &shade_frame, py::arg("mesh"), py::arg("joint_rotations"), py::arg("positions"),
          py::arg("world"), py::arg("lighting"), py::arg("model") = shading.model,
          py::arg("phong_exponent") = shading.phong_exponent,
          py::arg("camera") = std::array<double, 3>{shading.camera[0], shading.camera[1], shading.camera[2]},
          py::arg("transmission") = shading.transmission, py::arg("threads") = bake.threads,
          py::arg("rgba_out") = py::none(), py::arg("visibility_out") = py::none(),
          "The run time for one frame (what the handler calls): the evaluated mesh's object-space positions (V, 3) "
          "and world matrix (4, 4) in, normals by Blender's rule, every per-vertex step fused. Returns (rgba (V, 4) "
          "float32: RGB clamped >= 0, alpha 1; ao (V,) float32 clamped to [0, 1]; info with timings), written into "
          "rgba_out / visibility_out when given (float32, C-contiguous, exact shape).");
}

py::dict report_dict(const vis::FitReport& report) {
    py::dict r;
    py::list joints;
    for (const auto& j : report.joints) {
        py::dict d;
        d["name"] = j.name;
        d["active"] = j.active;
        d["max_angle_degrees"] = j.max_angle_degrees;
        d["feature_directions"] = j.feature_directions;
        d["reason"] = j.reason;
        joints.append(d);
    }
    r["joints"] = joints;
    r["training_frames"] = report.training_frames;
    r["holdout_frames"] = report.holdout_frames;
    r["zh_fit"] = errors_dict(report.zh_fit);
    r["model_training"] = errors_dict(report.model_training);
    r["model_holdout"] = errors_dict(report.model_holdout);
    r["model_holdout_unpruned"] = errors_dict(report.model_holdout_unpruned);
    r["ridge_relative"] = report.ridge_relative;
    r["ridge_curve"] = report.ridge_curve;
    r["constant_vertices"] = report.constant_vertices;
    r["stored_joint_blocks"] = report.stored_joint_blocks;
    r["stored_directions"] = report.stored_directions;
    r["model_bytes"] = report.model_bytes;
    r["dense_bytes"] = report.dense_bytes;
    r["seconds_zh_fit"] = report.seconds_zh_fit;
    r["seconds_linear"] = report.seconds_linear;
    return r;
}

py::tuple fit_model(const vis::TrainingSet& set, const std::vector<std::pair<bool, bool>>& influence, int lobes,
                    vis::PoseFeatures features, double joint_tolerance_degrees, int holdout_stride,
                    double constant_tolerance, double prune_tolerance, double feature_tolerance, int zh_iterations,
                    int frame_zh_iterations, double axis_prior, int threads, py::object progress) {
    vis::FitSettings s;
    s.lobes = lobes;
    s.features = features;
    s.joint_tolerance_degrees = joint_tolerance_degrees;
    s.holdout_stride = holdout_stride;
    s.constant_tolerance = constant_tolerance;
    s.prune_tolerance = prune_tolerance;
    s.feature_tolerance = feature_tolerance;
    s.zh_iterations = zh_iterations;
    s.frame_zh_iterations = frame_zh_iterations;
    s.axis_prior = axis_prior;
    s.threads = threads;
    std::vector<vis::BoneInfluence> inf;
    for (const auto& [deforms, rigid] : influence) inf.push_back({deforms, rigid});
    PyProgress py_progress(progress);
    vis::FitReport report;
    Model model;
    try {
        py::gil_scoped_release release;
        model = std::make_shared<vis::PoseModel>(vis::fit_pose_model(set, inf, s, py_progress.progress(), &report));
    } catch (const penumbra::Cancelled&) {
        py_progress.rethrow_if_failed();
        throw;
    }
    py_progress.rethrow_if_failed();
    return py::make_tuple(model, report_dict(report));
}

}  // namespace

void bind_visibility_model(py::module_& m) {
    bind_shading_mesh(m);
    bind_pose_model(m);
    const vis::FitSettings fit;  // every default below is the core's own
    m.def("fit_model", &fit_model, py::arg("training_set"), py::arg("bone_influence"), py::arg("lobes") = fit.lobes,
          py::arg("features") = fit.features, py::arg("joint_tolerance_degrees") = fit.joint_tolerance_degrees,
          py::arg("holdout_stride") = fit.holdout_stride, py::arg("constant_tolerance") = fit.constant_tolerance,
          py::arg("prune_tolerance") = fit.prune_tolerance, py::arg("feature_tolerance") = fit.feature_tolerance,
          py::arg("zh_iterations") = fit.zh_iterations,
          py::arg("frame_zh_iterations") = fit.frame_zh_iterations,
          py::arg("axis_prior") = fit.axis_prior, py::arg("threads") = fit.threads, py::arg("progress") = py::none(),
          "Fits ZH lobes per vertex and frame and the linear pose model (paper §3.1). bone_influence: one "
          "(deforms_mesh, rigid_for_whole_mesh) pair per bone of the training set. Returns (model, report).");
}

}  // namespace penumbra::bindings
