// _penumbra.visibility.TrainingSet: baked visibility of a deforming mesh,
// frame by frame (core/visibility/visibility_bake.hpp, training_set), and the
// Embree scene kept between frames of a bake.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "arrays.hpp"
#include "bindings.hpp"
#include "common/error.hpp"
#include "progress.hpp"
#include "visibility/model_file.hpp"
#include "visibility/visibility_bake.hpp"

namespace py = pybind11;
namespace vis = penumbra::visibility;

namespace penumbra::bindings {

namespace {

using Occluders = std::vector<std::pair<Floats, Indices>>;

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

vis::TriangleMesh mesh_from(const Floats& positions, const Indices& triangles, const char* what) {
    vis::TriangleMesh m;
    m.positions = triples(positions, (std::string(what) + " positions").c_str());
    m.triangles = indices(triangles, (std::string(what) + " triangles").c_str(), true);
    return m;
}

vis::TrainingSet make_training_set(std::size_t vertex_count, std::uint64_t topology_hash,
                                   std::vector<std::string> bone_names, int order, int rays,
                                   vis::BelowHorizon below_horizon, vis::Weighting weighting, double offset_scale) {
    vis::TrainingSet s;
    s.vertex_count = vertex_count;
    s.topology_hash = topology_hash;
    s.bone_names = std::move(bone_names);
    s.settings.order = order;
    s.settings.rays = rays;
    s.settings.below_horizon = below_horizon;
    s.settings.weighting = weighting;
    s.settings.offset_scale = offset_scale;
    vis::check_bake_settings(s.settings);
    return s;
}

vis::FrameGeometry frame_geometry(const vis::TrainingSet& s, const Floats& positions, const Floats& normals,
                                  const Indices& triangles, const Occluders& occluders) {
    vis::FrameGeometry g;
    g.mesh = mesh_from(positions, triangles, "mesh");
    g.normals = triples(normals, "normals");
    if (g.mesh.vertex_count() != s.vertex_count)
        throw py::value_error("the mesh has " + std::to_string(g.mesh.vertex_count()) +
                              " vertices in this frame, the training set " + std::to_string(s.vertex_count) +
                              " (a modifier changes the topology between frames?)");
    for (const auto& [p, t] : occluders) g.occluders.push_back(mesh_from(p, t, "occluder"));
    return g;
}

py::dict bake_stats_dict(const vis::FrameBakeStats& stats) {
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
}

py::dict bake_frame(vis::TrainingSet& s, double frame, const Floats& positions, const Floats& normals,
                    const Indices& triangles, const Indices& neighbours, const Floats& bone_rotations,
                    const Occluders& occluders, int threads, py::object progress, vis::SceneBuild scene_build) {
    const vis::FrameGeometry g = frame_geometry(s, positions, normals, triangles, occluders);
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
        BakerLoan loan = borrow_baker(settings, scene_build);
        loan.baker->bake(g, nb, f.visibility.data(), py_progress.progress(), &stats);
    } catch (const penumbra::Cancelled&) {
        py_progress.rethrow_if_failed();
        throw;
    }
    py_progress.rethrow_if_failed();
    s.frames.push_back(std::move(f));
    return bake_stats_dict(stats);
}

vis::TrainingSet subset(const vis::TrainingSet& s, const std::vector<std::size_t>& keep) {
    vis::TrainingSet out = s;
    out.frames.clear();
    for (auto i : keep) {
        if (i >= s.frames.size()) throw py::index_error("frame index out of range");
        out.frames.push_back(s.frames[i]);
    }
    return out;
}

void bind_frames(py::class_<vis::TrainingSet>& c) {
    c.def("__len__", [](const vis::TrainingSet& s) { return s.frames.size(); })
        .def_property_readonly("frame_numbers", [](const vis::TrainingSet& s) {
            std::vector<double> out;
            for (const auto& f : s.frames) out.push_back(f.frame);
            return out;
        })
        .def("visibility", [](const vis::TrainingSet& s, std::size_t i) {
            if (i >= s.frames.size()) throw py::index_error("frame index out of range");
            const py::ssize_t n_sh = s.settings.order * s.settings.order;
            return to_array(s.frames[i].visibility, {py::ssize_t(s.vertex_count), n_sh});
        }, py::arg("index"), "(V, order²) SH visibility of the index-th frame, in the vertices' frames.")
        .def("bone_rotations", [](const vis::TrainingSet& s, std::size_t i) {
            if (i >= s.frames.size()) throw py::index_error("frame index out of range");
            return to_array(s.frames[i].bone_rotations, {py::ssize_t(s.bone_names.size()), 3, 3});
        }, py::arg("index"))
        .def("subset", &subset, py::arg("indices"), "A copy holding only the given frames (by index).");
}

void bind_files(py::class_<vis::TrainingSet>& c) {
    c.def("save", [](const vis::TrainingSet& s, const std::string& path) {
        py::gil_scoped_release release;
        vis::write_training_set(path, s);
    }, py::arg("path"), "Writes the set atomically (.pvis).")
        .def_static("load", [](const std::string& path) {
            py::gil_scoped_release release;
            return vis::read_training_set(path);
        }, py::arg("path"))
        .def_static("merge", [](const std::vector<vis::TrainingSet>& pieces) { return vis::merge_training_sets(pieces); },
                    py::arg("pieces"), "One set from pieces of the same bake; frames sorted, duplicates kept once.");
}

void bind_properties(py::class_<vis::TrainingSet>& c) {
    c.def_property_readonly("vertex_count", [](const vis::TrainingSet& s) { return s.vertex_count; })
        .def_property_readonly("topology_hash", [](const vis::TrainingSet& s) { return s.topology_hash; })
        .def_property_readonly("bone_names", [](const vis::TrainingSet& s) { return s.bone_names; })
        .def_property_readonly("order", [](const vis::TrainingSet& s) { return s.settings.order; })
        .def_property_readonly("rays", [](const vis::TrainingSet& s) { return s.settings.rays; })
        .def_property_readonly("below_horizon", [](const vis::TrainingSet& s) { return s.settings.below_horizon; });
}

}  // namespace

void bind_visibility_training(py::module_& m) {
    const vis::BakeSettings bake;  // every default below is the core's own
    py::class_<vis::TrainingSet> c(m, "TrainingSet",
        "Baked visibility of a deforming mesh, frame by frame, with the pose of each frame. Bake pieces in "
        "separate processes, save them, and merge them before the fit.");
    c.def(py::init(&make_training_set), py::arg("vertex_count"), py::arg("topology_hash"), py::arg("bone_names"),
          py::arg("order") = bake.order, py::arg("rays") = bake.rays, py::arg("below_horizon") = bake.below_horizon,
          py::arg("weighting") = bake.weighting, py::arg("offset_scale") = bake.offset_scale);
    c.def("bake_frame", &bake_frame, py::arg("frame"), py::arg("positions"), py::arg("normals"), py::arg("triangles"),
          py::arg("neighbours"), py::arg("bone_rotations"), py::arg("occluders") = Occluders{},
          py::arg("threads") = bake.threads, py::arg("progress") = py::none(),
          // FrameBaker's own default; the build quality is no bake setting.
          py::arg("scene_build") = vis::SceneBuild::Medium,
          "Bakes one frame (world-space positions, normals, triangles; occluders as (positions, triangles) pairs) "
          "and appends it. Returns ray counts. Releases the GIL; progress(fraction) -> False cancels.");
    bind_files(c);
    bind_properties(c);
    bind_frames(c);

    m.def("release_bake_cache", [] {
        py::gil_scoped_release release;
        release_baker();
    }, "Frees the Embree scene kept between bake_frame calls (the add-on calls it when a bake ends).");
}

}  // namespace penumbra::bindings
