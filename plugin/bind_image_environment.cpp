// _penumbra.image.environment_radiance: the World that Environment Textures
// and colours light, resampled onto a latlong grid (image/environment_lookup.hpp).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>
#include <vector>

#include "arrays.hpp"
#include "bindings.hpp"
#include "common/error.hpp"
#include "enums.hpp"
#include "image/environment_lookup.hpp"
#include "numpy_image.hpp"
#include "progress.hpp"

namespace py = pybind11;

namespace penumbra::bindings {

namespace {

Eigen::Vector3d vector3(const py::handle& value, const char* what) {
    const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
    if (!a || a.size() != 3) throw py::value_error(std::string(what) + " must be 3 numbers");
    return {a.data()[0], a.data()[1], a.data()[2]};
}

LookupStep lookup_step(const py::handle& value) {
    const py::tuple step = py::cast<py::tuple>(value);
    if (step.size() != 3) throw py::value_error("a lookup step must be (A (3, 3), b (3,), normalize)");
    LookupStep out;
    out.a = matrix3(step[0], "a lookup step's A");
    out.b = vector3(step[1], "a lookup step's b");
    out.normalize = py::cast<bool>(step[2]);
    return out;
}

// A term from its dict; its image (if any) goes to `images`, which outlives the call.
EnvironmentTerm environment_term(const py::dict& d, std::vector<Image>& images) {
    EnvironmentTerm term;
    term.scale = d.contains("scale") ? py::cast<double>(d["scale"]) : 1.0;
    if (d.contains("colour")) term.colour = vector3(d["colour"], "a term's colour");
    if (d.contains("projection")) term.projection = py::cast<EnvironmentProjection>(d["projection"]);
    if (d.contains("closest")) term.closest = py::cast<bool>(d["closest"]);
    if (d.contains("steps"))
        for (const py::handle step : d["steps"]) term.steps.push_back(lookup_step(step));
    if (d.contains("pixels") && !d["pixels"].is_none())
        images.push_back(array_to_image(py::cast<py::array>(d["pixels"]), "a term's pixels"));
    return term;
}

py::array_t<float> environment_radiance(const py::list& terms, int width, int supersampling,
                                        const py::object& progress) {
    std::vector<Image> images;
    images.reserve(terms.size());
    std::vector<EnvironmentTerm> parsed;
    std::vector<long> image_of;  // index into images, −1 for a uniform term
    for (const py::handle t : terms) {
        const std::size_t before = images.size();
        parsed.push_back(environment_term(py::cast<py::dict>(t), images));
        image_of.push_back(images.size() > before ? long(before) : -1);
    }
    // Pointers only once `images` no longer grows.
    for (std::size_t i = 0; i < parsed.size(); ++i)
        parsed[i].image = image_of[i] < 0 ? nullptr : &images[std::size_t(image_of[i])];
    PyProgress py_progress(progress);
    Image out;
    try {
        py::gil_scoped_release release;
        out = penumbra::environment_radiance(parsed, width, supersampling, 0, py_progress.progress());
    } catch (const Cancelled&) {
        py_progress.rethrow_if_failed();
        throw;
    }
    return image_to_array(std::move(out));
}

}  // namespace

void bind_image_environment(py::module_& m) {
    bind_enum<EnvironmentProjection>(m, "EnvironmentProjection", "projection",
        {{"EQUIRECTANGULAR", EnvironmentProjection::equirectangular},
         {"MIRROR_BALL", EnvironmentProjection::mirror_ball}},
        "An Environment Texture's projection, by Blender's names.");
    m.def("environment_radiance", &environment_radiance, py::arg("terms"), py::arg("width"),
          py::arg("supersampling") = 2, py::arg("progress") = py::none(),
    "The World lit by `terms` on a latlong grid of world directions: float32 (width/2, width, 3), "
    "Σ scale·value(m(d)), each cell the solid-angle-weighted mean of supersampling² lookups. A term is a dict: "
    "scale (its mix weight × Strength, default 1), colour (3,) for a uniform term, or pixels (H, W, 3|4), row 0 = "
    "the top, looked up as Blender's Environment Texture does with projection ('EQUIRECTANGULAR' or "
    "'MIRROR_BALL'), closest (Closest interpolation, else bilinear) and steps [(A (3, 3), b (3,), normalize)], "
    "the Mapping / Vector Rotate maps x -> A x + b applied to the view direction in order. NaN pixels pass "
    "through. progress(fraction) -> False cancels.");
}

}  // namespace penumbra::bindings
