// The durable write (core/common/durable_file.hpp) for the add-on's own
// files, so that Python publishes a file the same way the core does.
#include <pybind11/pybind11.h>

#include <string>
#include <string_view>

#include "bindings.hpp"
#include "common/durable_file.hpp"

namespace py = pybind11;

namespace penumbra::bindings {

void bind_files(py::module_& m) {
    m.def("write_file_durably", [](const std::string& path, const py::bytes& data) {
        const std::string_view bytes = data;
        py::gil_scoped_release release;
        write_file_durably(path, bytes);
    }, py::arg("path"), py::arg("data"),
    "Writes `data` (bytes) to `path` whole or not at all, and so that it survives a power cut: a temporary "
    "beside it, fsync, rename over `path`, fsync of the folder (what the core does for models, training-set "
    "pieces and images). The folder must exist. Raises IoError (an OSError) if any step fails: before the "
    "rename `path` keeps its old contents, and no temporary is left behind.");

    m.def("replace_file_durably", [](const std::string& source, const std::string& target) {
        py::gil_scoped_release release;
        replace_file_durably(source, target);
    }, py::arg("source"), py::arg("target"),
    "os.replace(source, target) that survives a power cut: fsyncs `source`, renames it over `target` (same file "
    "system), fsyncs the target's folder (and the source's when another). Raises IoError (an OSError) if any "
    "step fails; before the rename both files are unchanged.");
}

}  // namespace penumbra::bindings
