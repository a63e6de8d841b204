// _penumbra.testing: hooks for tests and benchmarks, kept apart from the API:
// failures injected into the parallel helper, a probe of that helper, the
// steps of durable writes and a failing fsync, and internals of the light-rig
// tool that renderers and tests inspect.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <mutex>
#include <string>

#include "arrays.hpp"
#include "bindings.hpp"
#include "common/error.hpp"
#include "common/fault_injection.hpp"
#include "common/parallel.hpp"
#include "enums.hpp"
#include "lights/angular_regions.hpp"
#include "lights/frame_lights.hpp"
#include "lights/sampling.hpp"

namespace py = pybind11;

namespace penumbra::bindings {

namespace {

// A loop of `count` blocks that each take about block_seconds and poll
// parallel_stop_requested(): for tests of failure, cancel and progress
// through the Python binding.
std::size_t parallel_probe(std::size_t count, std::size_t block, int threads, double block_seconds,
                           const std::string& stage, py::object progress) {
    Progress p;
    if (!progress.is_none())
        p = Progress([progress](double f) {
            py::gil_scoped_acquire gil;
            return progress(f).cast<bool>();
        });
    std::size_t ran = 0;
    std::mutex m;
    py::gil_scoped_release release;
    parallel_for(count * block, {threads, block, stage.c_str()}, [&](std::size_t b, std::size_t e) {
        const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(block_seconds);
        while (std::chrono::steady_clock::now() < until && !parallel_stop_requested()) {}
        std::lock_guard<std::mutex> lock(m);
        ran += e - b;
    }, p);
    return ran;
}

void bind_parallel_hooks(py::module_& t) {
    bind_enum<testing::WorkerFailure>(t, "WorkerFailure", "kind",
        {{"NONE", testing::WorkerFailure::none}, {"RUNTIME_ERROR", testing::WorkerFailure::runtime_error},
         {"BAD_ALLOC", testing::WorkerFailure::bad_alloc}},
        "What an injected worker failure throws: nothing (NONE clears one), std::runtime_error or std::bad_alloc.");

    t.def("inject_worker_failure", &testing::inject_worker_failure, py::arg("stage"),
          py::arg("kind") = testing::WorkerFailure::runtime_error,
    "The next parallel loop whose stage starts with `stage` ('lights', 'colormap', 'sh', 'visibility', or a "
    "full stage name) throws `kind` from one of its blocks, on a worker thread when it has one; one-shot. "
    "kind=NONE clears it.");

    t.def("parallel_probe", &parallel_probe, py::arg("count"), py::arg("block") = 1, py::arg("threads") = 0,
          py::arg("block_seconds") = 0.001, py::arg("stage") = "testing.probe", py::arg("progress") = py::none(),
          "Runs the core's parallel helper on busy blocks; returns how many indices ran.");
}

void bind_durable_write_hooks(py::module_& t) {
    bind_enum<testing::FsyncFailure>(t, "FsyncFailure", "kind",
        {{"NONE", testing::FsyncFailure::none}, {"FILE", testing::FsyncFailure::file},
         {"FOLDER", testing::FsyncFailure::folder}},
        "Which fsync of a durable write an injected failure hits: none (NONE clears one), the written file's, or "
        "its folder's after the rename.");

    t.def("record_durable_steps", &testing::record_durable_steps,
    "Starts recording the steps of every durable write (models, pieces, images, write_file_durably, "
    "replace_file_durably), forgetting earlier ones.");

    t.def("recorded_durable_steps", &testing::recorded_durable_steps,
    "The steps recorded since record_durable_steps(), in order, and stops recording: 'fsync file <path>', "
    "'rename <from> -> <to>', 'fsync folder <folder>'.");

    t.def("inject_fsync_failure", &testing::inject_fsync_failure, py::arg("kind") = testing::FsyncFailure::file,
    "The next durable write's fsync of `kind` (FILE or FOLDER) fails with EIO, as a failing disk's would; "
    "one-shot. kind=NONE clears it.");
}

py::dict light_region_table(const py::array& directions, int cells_per_face, double lobe_half_angle) {
    const lights::AngularRegionTable t(vectors3(directions, "directions", true), cells_per_face, lobe_half_angle);
    std::vector<double> radius(t.region_count());
    for (int r = 0; r < t.region_count(); ++r) radius[r] = t.radius(r);
    py::dict out;
    out["offsets"] = t.offsets();
    out["lights"] = t.items();
    out["radius"] = radius;
    out["cells_per_face"] = t.cells_per_face();
    return out;
}

void bind_light_hooks(py::module_& t) {
    t.def("light_region_table", &light_region_table, py::arg("directions"), py::arg("cells_per_face") = 6,
          py::arg("lobe_half_angle") = 1.5707963267948966,
    "Angular-region table (paper §4.1) for renderers: CSR offsets and light indices per cube-map region.");

    t.def("light_region_of", [](const py::array& normals, int cells_per_face) {
        const lights::AngularRegionTable table({}, cells_per_face);
        std::vector<int> out;
        for (const auto& n : vectors3(normals, "normals", true)) out.push_back(table.region_of(n));
        return out;
    }, py::arg("normals"), py::arg("cells_per_face") = 6,
    "Cube-map region index of each direction: (face·g + row)·g + column, faces +x, −x, +y, −y, +z, −z.");

    t.def("light_sample_points", [](int count, bool blue_noise) {
        const auto p = lights::sample_points(count, blue_noise);
        py::array_t<double> out({py::ssize_t(p.size()), py::ssize_t(2)});
        for (std::size_t i = 0; i < p.size(); ++i) {
            out.mutable_at(i, 0) = p[i].x();
            out.mutable_at(i, 1) = p[i].y();
        }
        return out;
    }, py::arg("count"), py::arg("blue_noise") = lights::LightOptions{}.blue_noise,
    "Halton (2, 3) points from index 1, optionally Lloyd-relaxed.");
}

}  // namespace

void bind_testing(py::module_& t) {
    bind_parallel_hooks(t);
    bind_durable_write_hooks(t);
    bind_light_hooks(t);
}

}  // namespace penumbra::bindings
