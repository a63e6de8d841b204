// _penumbra: the Python face of penumbra_core. Thin: numpy in and out, the
// GIL released while C++ works, every C++ error a Python exception.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "common/build_info.hpp"
#include "common/error.hpp"

namespace py = pybind11;

PYBIND11_MODULE(_penumbra, m) {
    m.doc() = "Penumbra's C++ core: image I/O, colour management, SH shading, light rigs, colour-map lookups.";
    m.attr("__version__") = PENUMBRA_VERSION;

    // Later registrations are tried first, so the most derived come last.
    static py::exception<penumbra::Error> error(m, "PenumbraError", PyExc_RuntimeError);
    static py::exception<penumbra::IoError> io_error(m, "IoError", PyExc_OSError);
    static py::exception<penumbra::Cancelled> cancelled(m, "Cancelled", error.ptr());
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p)
                std::rethrow_exception(p);
        } catch (const penumbra::Cancelled& e) {
            PyErr_SetString(cancelled.ptr(), e.what());
        } catch (const penumbra::ArgumentError& e) {
            PyErr_SetString(PyExc_ValueError, e.what());
        } catch (const penumbra::IoError& e) {
            PyErr_SetString(io_error.ptr(), e.what());
        } catch (const penumbra::Error& e) {
            PyErr_SetString(error.ptr(), e.what());
        }
    });

    m.def("build_info", [] {
        auto info = penumbra::build_info();
        info["compiler"] = PENUMBRA_COMPILER;
        info["python"] = PY_VERSION;
        return info;
    }, "Compiler, SIMD level and the versions of OpenImageIO, OpenColorIO, Embree and Eigen in this build.");

    penumbra::bindings::bind_image(m);
    penumbra::bindings::bind_color(m);
    penumbra::bindings::bind_sh(m);
    penumbra::bindings::bind_sh_operators(m);
    penumbra::bindings::bind_shading(m);
    penumbra::bindings::bind_visibility(m);
    penumbra::bindings::bind_lights(m);
    penumbra::bindings::bind_colormap(m);
    penumbra::bindings::bind_settings(m);
    penumbra::bindings::bind_testing(m);
}
