// _penumbra: the Python face of penumbra_core. Thin: numpy in and out, the
// GIL released while C++ works, every C++ error a Python exception.
//
// One submodule per part of the core (image, color, sh, visibility, lights,
// colormap) and `testing` for the hooks tests and benchmarks use. The top
// level keeps only what belongs to the whole module (__version__,
// build_info, settings_spec, the exceptions, the durable file writes every
// tool publishes through) and four aliases of sh and
// colormap functions that scripts reach for first.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>

#include "bindings.hpp"
#include "common/build_info.hpp"
#include "common/error.hpp"

namespace py = pybind11;

namespace {

void bind_exceptions(py::module_& m) {
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
}

// m.def_submodule, also entered in sys.modules, so that `import
// _penumbra.lights` and `from _penumbra.lights import RigBuilder` work. When
// the add-on loads the module as penumbra._penumbra, the submodule is entered
// under that name too.
py::module_ submodule(py::module_& m, const char* name, const char* doc) {
    py::module_ sub = m.def_submodule(name, doc);
    py::dict modules = py::module_::import("sys").attr("modules");
    modules[py::str(std::string("_penumbra.") + name)] = sub;
    modules[sub.attr("__name__")] = sub;
    return sub;
}

}  // namespace

PYBIND11_MODULE(_penumbra, m) {
    using namespace penumbra::bindings;
    m.doc() = "Penumbra's C++ core: image I/O, colour management, SH shading, visibility, light rigs, colour-map "
              "lookups, one submodule each.";
    m.attr("__version__") = PENUMBRA_VERSION;
    bind_exceptions(m);
    m.def("build_info", [] {
        auto info = penumbra::build_info();
        info["compiler"] = PENUMBRA_COMPILER;
        info["python"] = PY_VERSION;
        return info;
    }, "Compiler, SIMD level and the versions of OpenImageIO, OpenColorIO, Embree and Eigen in this build.");

    // In dependency order: a submodule's signatures name types registered before it.
    py::module_ image = submodule(m, "image", "Images, numbered sequences and videos as float32 numpy arrays.");
    bind_image(image);
    py::module_ color = submodule(m, "color", "Colour management with OpenColorIO.");
    bind_color(color);
    py::module_ sh = submodule(m, "sh", "Spherical harmonics: basis, rotation, projection, BRDF operators, shading.");
    bind_sh(sh);
    bind_sh_operators(sh);
    bind_sh_shading(sh);
    py::module_ visibility = submodule(m, "visibility",
                                       "Shadowed relighting: baked visibility, ZH lobes and the linear pose model.");
    bind_visibility(visibility);
    py::module_ lights = submodule(m, "lights", "Light rigs from HDR images, sequences and videos.");
    bind_lights(lights);
    py::module_ colormap = submodule(m, "colormap",
                                     "Pre-filtered colour-map lookups, ColorRamps, microsurface statistics.");
    bind_colormap(colormap);
    bind_settings(m);
    bind_files(m);
    py::module_ testing = submodule(m, "testing", "Hooks for tests and benchmarks; not for add-on code.");
    bind_testing(testing);

    // The same function objects, under the names scripts have always used.
    m.attr("sh_eval") = sh.attr("eval");
    m.attr("phong_operator") = sh.attr("phong_operator");
    m.attr("project_environment") = sh.attr("project_environment");
    m.attr("colormap_lut") = colormap.attr("lut");
}
