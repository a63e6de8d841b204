// _penumbra.testing: hooks for tests and benchmarks, kept apart from the API.
#include <pybind11/pybind11.h>

#include <chrono>
#include <mutex>
#include <string>

#include "bindings.hpp"
#include "common/error.hpp"
#include "common/fault_injection.hpp"
#include "common/parallel.hpp"

namespace py = pybind11;

namespace penumbra::bindings {

void bind_testing(py::module_& m) {
    py::module_ t = m.def_submodule("testing", "Hooks for tests and benchmarks; not for add-on code.");

    t.def("inject_worker_failure", [](const std::string& stage, const std::string& kind) {
        testing::WorkerFailure failure = testing::WorkerFailure::none;
        if (kind == "runtime_error") failure = testing::WorkerFailure::runtime_error;
        else if (kind == "bad_alloc") failure = testing::WorkerFailure::bad_alloc;
        else if (kind != "none") throw ArgumentError("kind must be 'runtime_error', 'bad_alloc' or 'none'");
        testing::inject_worker_failure(stage, failure);
    }, py::arg("stage"), py::arg("kind") = "runtime_error",
    "The next parallel loop whose stage starts with `stage` ('lights', 'colormap', 'sh', 'visibility', or a "
    "full stage name) throws `kind` from one of its blocks, on a worker thread when it has one; one-shot. "
    "kind='none' clears it.");

    t.def("parallel_probe", [](std::size_t count, std::size_t block, int threads, double block_seconds,
                               const std::string& stage, py::object progress) {
        // A loop of `count` blocks that each take about block_seconds and
        // poll parallel_stop_requested(): for tests of failure, cancel and
        // progress through the Python binding.
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
    }, py::arg("count"), py::arg("block") = 1, py::arg("threads") = 0, py::arg("block_seconds") = 0.001,
    py::arg("stage") = "testing.probe", py::arg("progress") = py::none(),
    "Runs the core's parallel helper on busy blocks; returns how many indices ran.");
}

}  // namespace penumbra::bindings
