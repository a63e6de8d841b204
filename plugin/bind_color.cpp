// _penumbra.color: colour management (OpenColorIO).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "color/color_config.hpp"
#include "common/error.hpp"
#include "numpy_image.hpp"
#include "progress.hpp"

namespace py = pybind11;

namespace penumbra::bindings {

void bind_color(py::module_& m) {
    py::class_<ColorConfig>(m, "Config",
        "An OpenColorIO config. Inside Blender, load Blender's own config (penumbra.color.blender_config_path()).")
        .def(py::init([](const std::string& path) { return ColorConfig::load(path); }), py::arg("path") = "",
             "Loads `path`, or $OCIO when empty.")
        .def_property_readonly("path", &ColorConfig::path)
        .def_property_readonly("scene_linear", &ColorConfig::scene_linear,
                               "Name of the colour space the scene_linear role points at.")
        .def_property_readonly("version", &ColorConfig::version)
        .def("colorspace_names", &ColorConfig::colorspace_names)
        .def("has_colorspace", &ColorConfig::has_colorspace, py::arg("name"))
        .def("convert", [](const ColorConfig& self, const py::array& pixels, const std::string& from_space,
                           const std::string& to_space, py::object progress) {
            Image image = array_to_image(pixels, "pixels");
            if (image.channels != 3)
                throw ArgumentError("convert needs (height, width, 3) RGB pixels");
            PyProgress callback(std::move(progress));
            try {
                py::gil_scoped_release release;
                self.convert(image, from_space, to_space, callback.progress());
            } catch (const Cancelled&) {
                callback.rethrow_if_failed();
                throw;
            }
            return image_to_array(std::move(image));
        }, py::arg("pixels"), py::arg("from_space"), py::arg("to_space"), py::arg("progress") = py::none(),
        "Returns a converted copy of (height, width, 3) pixels.")
        .def("to_scene_linear", [](const ColorConfig& self, const py::array& pixels, const std::string& from_space) {
            Image image = array_to_image(pixels, "pixels");
            if (image.channels != 3)
                throw ArgumentError("to_scene_linear needs (height, width, 3) RGB pixels");
            {
                py::gil_scoped_release release;
                self.to_scene_linear(image, from_space);
            }
            return image_to_array(std::move(image));
        }, py::arg("pixels"), py::arg("from_space"),
        "Returns a copy of (height, width, 3) pixels converted from `from_space` to the scene_linear role.");
}

}  // namespace penumbra::bindings
