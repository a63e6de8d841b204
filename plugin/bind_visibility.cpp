// Bindings for core/visibility: the visibility baker (bake, merge, fit, model
// files) and its run time (pose → shade). numpy in and out; inputs are copied
// into C++ buffers before the GIL is released.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <array>
#include <cmath>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "common/error.hpp"
#include "progress.hpp"
#include "sh/pose_shading.hpp"
#include "visibility/mesh_frames.hpp"
#include "visibility/model_file.hpp"
#include "visibility/pose_model.hpp"
#include "visibility/runtime_shading.hpp"
#include "visibility/visibility_bake.hpp"
#include "visibility/zh_fit.hpp"

namespace py = pybind11;
namespace vis = penumbra::visibility;

namespace penumbra::bindings {

namespace {

using Floats = py::array_t<float, py::array::c_style | py::array::forcecast>;
using Doubles = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Indices = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;

std::string shape_of(const py::array& a) {
    std::string s = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
    return s + (a.ndim() == 1 ? ",)" : ")");
}

// (N, 3) or flat 3N float array -> vector.
std::vector<float> triples(const Floats& a, const char* what) {
    const bool ok = (a.ndim() == 2 && a.shape(1) == 3) || (a.ndim() == 1 && a.shape(0) % 3 == 0);
    if (!ok) throw py::value_error(std::string(what) + " must have shape (N, 3), got " + shape_of(a));
    return std::vector<float>(a.data(), a.data() + a.size());
}

std::vector<std::uint32_t> indices(const Indices& a, const char* what, bool triples_only) {
    if (triples_only && !((a.ndim() == 2 && a.shape(1) == 3) || (a.ndim() == 1 && a.shape(0) % 3 == 0)))
        throw py::value_error(std::string(what) + " must have shape (M, 3), got " + shape_of(a));
    if (!triples_only && a.ndim() != 1) throw py::value_error(std::string(what) + " must be 1-dimensional");
    std::vector<std::uint32_t> out(a.size());
    const std::int64_t* p = a.data();
    for (py::ssize_t i = 0; i < a.size(); ++i) {
        if (p[i] < 0 || p[i] > 0xFFFFFFFFll) throw py::value_error(std::string(what) + " holds a negative or huge index");
        out[i] = std::uint32_t(p[i]);
    }
    return out;
}

// (B, 3, 3) or (B, 9) rotations -> B × 9 floats.
std::vector<float> rotations(const Floats& a, std::size_t expected, const char* what) {
    const bool ok = (a.ndim() == 3 && a.shape(1) == 3 && a.shape(2) == 3) || (a.ndim() == 2 && a.shape(1) == 9) ||
                    (a.ndim() == 1 && a.shape(0) == 0);
    if (!ok) throw py::value_error(std::string(what) + " must have shape (B, 3, 3), got " + shape_of(a));
    const std::size_t count = a.ndim() == 1 ? 0 : std::size_t(a.shape(0));
    if (count != expected)
        throw py::value_error(std::string(what) + ": expected " + std::to_string(expected) + " rotations, got " +
                              std::to_string(count));
    return std::vector<float>(a.data(), a.data() + a.size());
}

template <typename T>
py::array_t<T> to_array(const std::vector<T>& v, std::vector<py::ssize_t> shape) {
    py::array_t<T> out(shape);
    std::copy(v.begin(), v.end(), out.mutable_data());
    return out;
}

vis::BelowHorizon below_from(const std::string& s) {
    if (s == "occluded") return vis::BelowHorizon::Occluded;
    if (s == "cast") return vis::BelowHorizon::Cast;
    throw py::value_error("below_horizon must be 'occluded' or 'cast', got '" + s + "'");
}
std::string below_name(vis::BelowHorizon b) { return b == vis::BelowHorizon::Cast ? "cast" : "occluded"; }

vis::Weighting weighting_from(const std::string& s) {
    if (s == "plain") return vis::Weighting::Plain;
    if (s == "cosine") return vis::Weighting::Cosine;
    throw py::value_error("weighting must be 'plain' or 'cosine', got '" + s + "'");
}

vis::PoseFeatures features_from(const std::string& s) {
    if (s == "matrix") return vis::PoseFeatures::RotationMatrix;
    if (s == "rotation_vector") return vis::PoseFeatures::RotationVector;
    throw py::value_error("features must be 'matrix' or 'rotation_vector', got '" + s + "'");
}
std::string features_name(vis::PoseFeatures f) {
    return f == vis::PoseFeatures::RotationVector ? "rotation_vector" : "matrix";
}

py::dict errors_dict(const vis::Errors& e) {
    py::dict d;
    d["sh_rms"] = e.sh_rms;
    d["ao_mean_abs"] = e.ao_mean_abs;
    d["ao_max_abs"] = e.ao_max_abs;
    d["samples"] = e.samples;
    return d;
}

vis::TriangleMesh mesh_from(const Floats& positions, const Indices& triangles, const char* what) {
    vis::TriangleMesh m;
    m.positions = triples(positions, (std::string(what) + " positions").c_str());
    m.triangles = indices(triangles, (std::string(what) + " triangles").c_str(), true);
    return m;
}

vis::SceneBuild scene_build_from(const std::string& s) {
    if (s == "high") return vis::SceneBuild::High;
    if (s == "medium") return vis::SceneBuild::Medium;
    if (s == "low") return vis::SceneBuild::Low;
    if (s == "refit") return vis::SceneBuild::Refit;
    throw py::value_error("scene_build must be 'high', 'medium', 'low' or 'refit', got '" + s + "'");
}

// The frame baker kept between bake_frame calls (a bake is frame after frame
// of one mesh: the ray set and the Embree scene carry over, the scene is only
// updated). One process-wide baker, lent to one call at a time; a call that
// finds it busy (another thread baking) or made for other settings uses a
// fresh one. Taken with the GIL released; the mutex is never held while
// Python runs.
struct BakerLoan {
    std::unique_lock<std::mutex> lock;
    vis::FrameBaker* baker = nullptr;
    std::unique_ptr<vis::FrameBaker> own;
};
// Never destroyed at exit (an Embree scene released during static
// destruction could outlive Embree); release_baker() frees it after a bake.
std::mutex& baker_mutex() {
    static auto* mutex = new std::mutex;
    return *mutex;
}
std::unique_ptr<vis::FrameBaker>& kept_baker() {
    static auto* kept = new std::unique_ptr<vis::FrameBaker>;
    return *kept;
}
void release_baker() {
    std::lock_guard<std::mutex> lock(baker_mutex());
    kept_baker().reset();
}
BakerLoan borrow_baker(const vis::BakeSettings& settings, vis::SceneBuild build) {
    std::mutex& mutex = baker_mutex();
    std::unique_ptr<vis::FrameBaker>& kept = kept_baker();
    BakerLoan loan;
    loan.lock = std::unique_lock<std::mutex>(mutex, std::try_to_lock);
    if (!loan.lock.owns_lock()) {
        loan.own = std::make_unique<vis::FrameBaker>(settings, build);
        loan.baker = loan.own.get();
        return loan;
    }
    const auto same = [&](const vis::BakeSettings& a) {
        return a.order == settings.order && a.rays == settings.rays && a.below_horizon == settings.below_horizon &&
               a.weighting == settings.weighting && a.offset_scale == settings.offset_scale;
    };
    if (!kept || !same(kept->settings()) || kept->scene_build() != build) {
        kept.reset();
        kept = std::make_unique<vis::FrameBaker>(settings, build);
    }
    kept->set_threads(settings.threads);
    loan.baker = kept.get();
    return loan;
}

// One PoseShader per SH order for the whole process: building one costs
// microseconds at order 4 and ~0.2 ms at order 8, and it caches the Phong
// operators of the exponents it has seen. PoseShader::shade is thread-safe,
// so the shared instance may serve concurrent calls. Taken with the GIL
// released: the mutex is only held to look up or build the shader, never
// while Python runs.
std::shared_ptr<const sh::PoseShader> shader_for(int order) {
    static std::mutex mutex;
    static std::array<std::shared_ptr<const sh::PoseShader>, 9> shaders;
    if (order < 1 || order > 8) throw penumbra::ArgumentError("SH order must be in [1, 8]");
    std::lock_guard<std::mutex> lock(mutex);
    auto& slot = shaders[std::size_t(order)];
    if (!slot) slot = std::make_shared<const sh::PoseShader>(order);
    return slot;
}

py::dict summary_dict(const vis::PoseModel& m) {
    py::dict d;
    for (const auto& [k, v] : m.summary) d[py::str(k)] = v;
    return d;
}

}  // namespace

void bind_visibility(py::module_& m) {
    // Every default below is the core's own, read from default-constructed settings.
    const vis::BakeSettings bake;
    const vis::FitSettings fit;
    const vis::ZhFitSettings zh;
    // Mesh helpers -----------------------------------------------------------
    m.def("visibility_reference_neighbours", [](std::size_t vertex_count, const Indices& polygon_sizes,
                                                const Indices& polygon_vertices) {
        const auto n = vis::reference_neighbours(vertex_count, indices(polygon_sizes, "polygon_sizes", false),
                                                 indices(polygon_vertices, "polygon_vertices", false));
        return to_array(n, {py::ssize_t(n.size())});
    }, py::arg("vertex_count"), py::arg("polygon_sizes"), py::arg("polygon_vertices"),
       "Reference neighbour of each vertex (the next vertex of the first polygon using it): fixes the tangent of "
       "its frame. Empty polygon_sizes: polygon_vertices are triangles.");

    m.def("visibility_vertex_frames", [](const Floats& positions, const Floats& normals, const Indices& triangles,
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
    }, py::arg("positions"), py::arg("normals"), py::arg("triangles"), py::arg("neighbours"),
       "Tangent frames (V, 3, 3), rows t, b, n, and counts of repaired normals and fallback tangents.");

    m.def("visibility_mesh_diagnostics", [](const Floats& positions, const Floats& normals, const Indices& triangles) {
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
    }, py::arg("positions"), py::arg("normals"), py::arg("triangles"),
       "Checks before a bake: bounding diagonal, signed volume, inward normals, degenerate faces and normals.");

    m.def("visibility_topology_hash", [](std::size_t vertex_count, const Indices& polygon_sizes,
                                         const Indices& polygon_vertices) {
        return vis::topology_hash(vertex_count, indices(polygon_sizes, "polygon_sizes", false),
                                  indices(polygon_vertices, "polygon_vertices", false));
    }, py::arg("vertex_count"), py::arg("polygon_sizes"), py::arg("polygon_vertices"),
       "FNV-1a 64 fingerprint of the polygon topology, stored in model files.");

    m.def("visibility_release_bake_cache", [] {
        py::gil_scoped_release release;
        release_baker();
    }, "Frees the Embree scene kept between bake_frame calls (the add-on calls it when a bake ends).");

    // Training sets ------------------------------------------------------------
    py::class_<vis::TrainingSet>(m, "VisibilityTrainingSet",
        "Baked visibility of a deforming mesh, frame by frame, with the pose of each frame. Bake pieces in "
        "separate processes, save them, and merge them before the fit.")
        .def(py::init([](std::size_t vertex_count, std::uint64_t topology_hash, std::vector<std::string> bone_names,
                         int order, int rays, const std::string& below_horizon, const std::string& weighting,
                         double offset_scale) {
            vis::TrainingSet s;
            s.vertex_count = vertex_count;
            s.topology_hash = topology_hash;
            s.bone_names = std::move(bone_names);
            s.settings.order = order;
            s.settings.rays = rays;
            s.settings.below_horizon = below_from(below_horizon);
            s.settings.weighting = weighting_from(weighting);
            s.settings.offset_scale = offset_scale;
            vis::check_bake_settings(s.settings);
            return s;
        }), py::arg("vertex_count"), py::arg("topology_hash"), py::arg("bone_names"), py::arg("order") = bake.order,
            py::arg("rays") = bake.rays, py::arg("below_horizon") = "occluded", py::arg("weighting") = "plain",
            py::arg("offset_scale") = bake.offset_scale)
        .def("bake_frame", [](vis::TrainingSet& s, double frame, const Floats& positions, const Floats& normals,
                              const Indices& triangles, const Indices& neighbours, const Floats& bone_rotations,
                              const std::vector<std::pair<Floats, Indices>>& occluders, int threads,
                              py::object progress, const std::string& scene_build) {
            const vis::SceneBuild build = scene_build_from(scene_build);
            vis::FrameGeometry g;
            g.mesh = mesh_from(positions, triangles, "mesh");
            g.normals = triples(normals, "normals");
            if (g.mesh.vertex_count() != s.vertex_count)
                throw py::value_error("the mesh has " + std::to_string(g.mesh.vertex_count()) +
                                      " vertices in this frame, the training set " + std::to_string(s.vertex_count) +
                                      " (a modifier changes the topology between frames?)");
            for (const auto& [p, t] : occluders) g.occluders.push_back(mesh_from(p, t, "occluder"));
            const auto nb = indices(neighbours, "neighbours", false);
            vis::TrainingFrame f;
            f.frame = frame;
            f.bone_rotations = rotations(bone_rotations, s.bone_names.size(), "bone_rotations");
            f.visibility.resize(s.vertex_count * s.settings.order * s.settings.order);
            vis::BakeSettings settings = s.settings;
            settings.threads = threads;
            PyProgress py_progress(progress);
            vis::FrameBakeStats stats;
            try {
                py::gil_scoped_release release;
                BakerLoan loan = borrow_baker(settings, build);
                loan.baker->bake(g, nb, f.visibility.data(), py_progress.progress(), &stats);
            } catch (const penumbra::Cancelled&) {
                py_progress.rethrow_if_failed();
                throw;
            }
            py_progress.rethrow_if_failed();
            s.frames.push_back(std::move(f));
            py::dict d;
            d["rays_cast"] = stats.rays_cast;
            d["rays_counted"] = stats.rays_counted;
            d["repaired_normals"] = stats.frames.repaired_normals;
            d["fallback_tangents"] = stats.frames.fallback_tangents;
            d["seconds_setup"] = stats.seconds_setup;
            d["seconds_build"] = stats.seconds_build;
            d["seconds_cast"] = stats.seconds_cast;
            d["scene_updated"] = stats.scene_updated;
            return d;
        }, py::arg("frame"), py::arg("positions"), py::arg("normals"), py::arg("triangles"), py::arg("neighbours"),
           py::arg("bone_rotations"), py::arg("occluders") = std::vector<std::pair<Floats, Indices>>{},
           py::arg("threads") = bake.threads, py::arg("progress") = py::none(), py::arg("scene_build") = "medium",
           "Bakes one frame (world-space positions, normals, triangles; occluders as (positions, triangles) pairs) "
           "and appends it. Returns ray counts. Releases the GIL; progress(fraction) -> False cancels.")
        .def("save", [](const vis::TrainingSet& s, const std::string& path) {
            py::gil_scoped_release release;
            vis::write_training_set(path, s);
        }, py::arg("path"), "Writes the set atomically (.pvis).")
        .def_static("load", [](const std::string& path) {
            py::gil_scoped_release release;
            return vis::read_training_set(path);
        }, py::arg("path"))
        .def_static("merge", [](const std::vector<vis::TrainingSet>& pieces) { return vis::merge_training_sets(pieces); },
                    py::arg("pieces"), "One set from pieces of the same bake; frames sorted, duplicates kept once.")
        .def_property_readonly("vertex_count", [](const vis::TrainingSet& s) { return s.vertex_count; })
        .def_property_readonly("topology_hash", [](const vis::TrainingSet& s) { return s.topology_hash; })
        .def_property_readonly("bone_names", [](const vis::TrainingSet& s) { return s.bone_names; })
        .def_property_readonly("order", [](const vis::TrainingSet& s) { return s.settings.order; })
        .def_property_readonly("rays", [](const vis::TrainingSet& s) { return s.settings.rays; })
        .def_property_readonly("below_horizon", [](const vis::TrainingSet& s) { return below_name(s.settings.below_horizon); })
        .def_property_readonly("frame_numbers", [](const vis::TrainingSet& s) {
            std::vector<double> out;
            for (const auto& f : s.frames) out.push_back(f.frame);
            return out;
        })
        .def("__len__", [](const vis::TrainingSet& s) { return s.frames.size(); })
        .def("visibility", [](const vis::TrainingSet& s, std::size_t i) {
            if (i >= s.frames.size()) throw py::index_error("frame index out of range");
            const py::ssize_t n_sh = s.settings.order * s.settings.order;
            return to_array(s.frames[i].visibility, {py::ssize_t(s.vertex_count), n_sh});
        }, py::arg("index"), "(V, order²) SH visibility of the index-th frame, in the vertices' frames.")
        .def("bone_rotations", [](const vis::TrainingSet& s, std::size_t i) {
            if (i >= s.frames.size()) throw py::index_error("frame index out of range");
            return to_array(s.frames[i].bone_rotations, {py::ssize_t(s.bone_names.size()), 3, 3});
        }, py::arg("index"))
        .def("subset", [](const vis::TrainingSet& s, const std::vector<std::size_t>& keep) {
            vis::TrainingSet out = s;
            out.frames.clear();
            for (auto i : keep) {
                if (i >= s.frames.size()) throw py::index_error("frame index out of range");
                out.frames.push_back(s.frames[i]);
            }
            return out;
        }, py::arg("indices"), "A copy holding only the given frames (by index).");

    // Pose model -----------------------------------------------------------------
    py::class_<vis::PoseModel, std::shared_ptr<vis::PoseModel>>(m, "VisibilityPoseModel",
        "The linear pose-space ZH visibility model of one mesh and armature.")
        .def_static("load", [](const std::string& path) {
            py::gil_scoped_release release;
            return std::make_shared<vis::PoseModel>(vis::read_pose_model(path));
        }, py::arg("path"), "Reads a .pzh file; a missing, truncated or corrupted file raises IoError.")
        .def("save", [](const vis::PoseModel& model, const std::string& path) {
            py::gil_scoped_release release;
            vis::write_pose_model(path, model);
        }, py::arg("path"), "Writes the model atomically.")
        .def_property_readonly("order", [](const vis::PoseModel& x) { return x.order; })
        .def_property_readonly("lobes", [](const vis::PoseModel& x) { return x.lobes; })
        .def_property_readonly("rays", [](const vis::PoseModel& x) { return x.rays; })
        .def_property_readonly("below_horizon", [](const vis::PoseModel& x) { return below_name(x.below_horizon); })
        .def_property_readonly("features", [](const vis::PoseModel& x) { return features_name(x.features); })
        .def_property_readonly("vertex_count", [](const vis::PoseModel& x) { return x.vertex_count; })
        .def_property_readonly("topology_hash", [](const vis::PoseModel& x) { return x.topology_hash; })
        .def_property_readonly("joints", [](const vis::PoseModel& x) { return x.joints; })
        .def_property_readonly("armature_bones", [](const vis::PoseModel& x) { return x.armature_bones; })
        .def_property_readonly("summary", &summary_dict)
        .def_property_readonly("constant_vertices", [](const vis::PoseModel& x) {
            std::size_t n = 0;
            for (std::size_t v = 0; v < x.vertex_count; ++v) n += x.joint_offsets[v] == x.joint_offsets[v + 1];
            return n;
        })
        .def("joints_per_vertex", [](const vis::PoseModel& x) {
            std::vector<std::uint32_t> n(x.vertex_count);
            for (std::size_t v = 0; v < x.vertex_count; ++v) n[v] = x.joint_offsets[v + 1] - x.joint_offsets[v];
            return to_array(n, {py::ssize_t(n.size())});
        })
        .def("synthesize", [](const vis::PoseModel& x, const Floats& joint_rotations, int threads) {
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
        }, py::arg("joint_rotations"), py::arg("threads") = bake.threads,
           "Paper §4.3 step 1: lobes for a pose. joint_rotations (J, 3, 3) in `joints` order. Returns "
           "(axes (V, c, 3) local, bands (V, c, order), params (V, c, 2 + order)).")
        .def("evaluate", [](const vis::PoseModel& x, const vis::TrainingSet& s, int threads) {
            vis::Errors e;
            {
                py::gil_scoped_release release;
                e = vis::evaluate_pose_model(x, s, threads);
            }
            return errors_dict(e);
        }, py::arg("frames"), py::arg("threads") = bake.threads,
           "Errors of the model against baked frames (poses it may never have seen).")
        .def("shade", [](const vis::PoseModel& x, const Floats& joint_rotations, const Floats& positions,
                         const Floats& normals, const Indices& triangles, const Indices& neighbours,
                         const Doubles& lighting, const std::string& model, double phong_exponent,
                         const std::array<double, 3>& camera, const std::array<double, 3>& transmission,
                         int threads) {
            const auto r = rotations(joint_rotations, x.joints.size(), "joint_rotations");
            const auto p = triples(positions, "positions"), n = triples(normals, "normals");
            const auto t = indices(triangles, "triangles", true), nb = indices(neighbours, "neighbours", false);
            const py::ssize_t n_sh = py::ssize_t(x.order) * x.order;
            if (lighting.ndim() != 2 || lighting.shape(0) != n_sh || lighting.shape(1) != 3)
                throw py::value_error("lighting must have shape (" + std::to_string(n_sh) + ", 3), got " + shape_of(lighting));
            Eigen::MatrixXd l(n_sh, 3);
            for (py::ssize_t i = 0; i < n_sh; ++i)
                for (int c = 0; c < 3; ++c) l(i, c) = lighting.at(i, c);
            sh::ShadingParameters sp;
            if (model == "diffuse") sp.model = sh::ShadingModel::diffuse;
            else if (model == "phong") sp.model = sh::ShadingModel::phong;
            else if (model == "translucent") sp.model = sh::ShadingModel::translucent;
            else throw py::value_error("model must be 'diffuse', 'phong' or 'translucent', got '" + model + "'");
            sp.phong_exponent = phong_exponent;
            sp.camera = Eigen::Vector3d(camera[0], camera[1], camera[2]);
            sp.transmission = transmission;
            sp.threads = threads;
            vis::RuntimeResult result;
            {
                py::gil_scoped_release release;
                const auto shader = shader_for(x.order);
                result = vis::shade_pose(x, *shader, r.data(), p, n, t, nb, l, sp);
            }
            py::dict info;
            info["seconds_pose_to_lobes"] = result.timings.pose_to_lobes;
            info["seconds_frames"] = result.timings.frames;
            info["seconds_shading"] = result.timings.shading;
            info["invalid_vertices"] = result.stats.invalid_vertices;
            info["repaired_normals"] = result.frame_stats.repaired_normals;
            return py::make_tuple(to_array(result.rgb, {py::ssize_t(x.vertex_count), 3}),
                                  to_array(result.visibility, {py::ssize_t(x.vertex_count)}), info);
        }, py::arg("joint_rotations"), py::arg("positions"), py::arg("normals"), py::arg("triangles"),
           py::arg("neighbours"), py::arg("lighting"), py::arg("model") = "diffuse",
           py::arg("phong_exponent") = sh::ShadingParameters{}.phong_exponent,
           // The defaults are the core's own (sh::ShadingParameters), never typed here again.
           py::arg("camera") = std::array<double, 3>{sh::ShadingParameters{}.camera[0], sh::ShadingParameters{}.camera[1],
                                                     sh::ShadingParameters{}.camera[2]},
           py::arg("transmission") = sh::ShadingParameters{}.transmission,
           py::arg("threads") = bake.threads,
           "The whole run time for one pose: lobes from the pose, frames from the deformed mesh, shading with the SH "
           "engine under lighting (order², 3). Returns (rgb (V, 3) float32, ao (V,) float32, info with timings).");

    m.def("fit_visibility_model", [](const vis::TrainingSet& set, const std::vector<std::pair<bool, bool>>& influence,
                                     int lobes, const std::string& features, double joint_tolerance_degrees,
                                     int holdout_stride, double constant_tolerance, double prune_tolerance,
                                     int zh_iterations, double axis_prior, int threads, py::object progress) {
        vis::FitSettings s;
        s.lobes = lobes;
        s.features = features_from(features);
        s.joint_tolerance_degrees = joint_tolerance_degrees;
        s.holdout_stride = holdout_stride;
        s.constant_tolerance = constant_tolerance;
        s.prune_tolerance = prune_tolerance;
        s.zh_iterations = zh_iterations;
        s.axis_prior = axis_prior;
        s.threads = threads;
        std::vector<vis::BoneInfluence> inf;
        for (const auto& [deforms, rigid] : influence) inf.push_back({deforms, rigid});
        PyProgress py_progress(progress);
        vis::FitReport report;
        std::shared_ptr<vis::PoseModel> model;
        try {
            py::gil_scoped_release release;
            model = std::make_shared<vis::PoseModel>(vis::fit_pose_model(set, inf, s, py_progress.progress(), &report));
        } catch (const penumbra::Cancelled&) {
            py_progress.rethrow_if_failed();
            throw;
        }
        py_progress.rethrow_if_failed();
        py::dict r;
        py::list joints;
        for (const auto& j : report.joints) {
            py::dict d;
            d["name"] = j.name;
            d["active"] = j.active;
            d["max_angle_degrees"] = j.max_angle_degrees;
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
        r["model_bytes"] = report.model_bytes;
        r["dense_bytes"] = report.dense_bytes;
        r["seconds_zh_fit"] = report.seconds_zh_fit;
        r["seconds_linear"] = report.seconds_linear;
        return py::make_tuple(model, r);
    }, py::arg("training_set"), py::arg("bone_influence"), py::arg("lobes") = fit.lobes, py::arg("features") = "matrix",
       py::arg("joint_tolerance_degrees") = fit.joint_tolerance_degrees, py::arg("holdout_stride") = fit.holdout_stride,
       py::arg("constant_tolerance") = fit.constant_tolerance,
       py::arg("prune_tolerance") = fit.prune_tolerance, py::arg("zh_iterations") = fit.zh_iterations,
       py::arg("axis_prior") = fit.axis_prior,
       py::arg("threads") = bake.threads, py::arg("progress") = py::none(),
       "Fits ZH lobes per vertex and frame and the linear pose model (paper §3.1). bone_influence: one "
       "(deforms_mesh, rigid_for_whole_mesh) pair per bone of the training set. Returns (model, report).");

    // ZH fitting on its own (tests, benchmarks) ----------------------------------
    m.def("zh_fit_lobes", [](const Doubles& sh, int lobes, py::object reference, int iterations, double axis_prior) {
        if (sh.ndim() != 2) throw py::value_error("sh must be (N, order²), got " + shape_of(sh));
        const int order = int(std::lround(std::sqrt(double(sh.shape(1)))));
        if (order * order != sh.shape(1)) throw py::value_error("sh rows need order² values");
        vis::ZhFitSettings s;
        s.order = order;
        s.lobes = lobes;
        s.iterations = iterations;
        s.axis_prior = axis_prior;
        const int d = lobes * vis::params_per_lobe(order);
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
            for (py::ssize_t i = 0; i < N; ++i)
                residual[i] = vis::fit_zh_lobes(s, in.data() + i * order * order, ref.empty() ? nullptr : ref.data() + i * d,
                                                out.data() + i * d);
        }
        return py::make_tuple(to_array(out, {N, lobes, vis::params_per_lobe(order)}), to_array(residual, {N}));
    }, py::arg("sh"), py::arg("lobes") = zh.lobes, py::arg("reference") = py::none(), py::arg("iterations") = zh.iterations,
       py::arg("axis_prior") = zh.axis_prior,
       "Fits ZH lobes to SH vectors (N, order²). Returns (params (N, lobes, 2 + order): Lambert (X, Y) then "
       "bands; squared residuals (N,)).");

    m.def("zh_params_to_sh", [](const Doubles& params) {
        if (params.ndim() != 3) throw py::value_error("params must be (N, lobes, 2 + order), got " + shape_of(params));
        const int lobes = int(params.shape(1)), order = int(params.shape(2)) - 2;
        if (order < 1 || order > 8 || lobes < 1 || lobes > vis::max_lobes)
            throw py::value_error("params must be (N, lobes 1..4, 2 + order 1..8)");
        const py::ssize_t N = params.shape(0);
        std::vector<double> out(N * order * order);
        for (py::ssize_t i = 0; i < N; ++i)
            vis::lobes_to_sh(order, lobes, params.data() + i * lobes * (order + 2), out.data() + i * order * order);
        return to_array(out, {N, py::ssize_t(order) * order});
    }, py::arg("params"), "Paper Eq. 1 for lobe parameters (N, lobes, 2 + order): (N, order²) SH.");

    m.def("zh_lambert_to_axis", [](double X, double Y) {
        const Eigen::Vector3d a = vis::lambert_to_axis(X, Y);
        return py::make_tuple(a.x(), a.y(), a.z());
    }, py::arg("X"), py::arg("Y"), "Inverse of the seam-free lobe-axis map (Lambert azimuthal equal-area about +z).");

    m.def("visibility_ambient_occlusion", [](const Doubles& sh) {
        if (sh.ndim() != 2) throw py::value_error("sh must be (N, order²)");
        const int order = int(std::lround(std::sqrt(double(sh.shape(1)))));
        if (order * order != sh.shape(1) || order < 1 || order > 8) throw py::value_error("sh rows need order² values");
        std::vector<double> out(sh.shape(0));
        for (py::ssize_t i = 0; i < sh.shape(0); ++i) out[i] = vis::ambient_occlusion(order, sh.data() + i * order * order);
        return to_array(out, {sh.shape(0)});
    }, py::arg("sh"), "Cosine-weighted visibility (AO) √(4π)(T_diffuse v)_00 of SH visibility vectors.");
}

}  // namespace penumbra::bindings
