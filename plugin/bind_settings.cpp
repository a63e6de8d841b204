// settings_spec(): the default and valid range of every setting the add-on
// mirrors, read from the core's settings structs (common/setting.hpp), so
// tests can check the add-on's properties against them.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "colormap/lookup.hpp"
#include "common/setting.hpp"
#include "lights/rig.hpp"
#include "sh/pose_shading.hpp"
#include "visibility/pose_fit.hpp"
#include "visibility/visibility_bake.hpp"

namespace py = pybind11;

namespace penumbra::bindings {

namespace {

template <class T>
py::dict spec(T default_value, const Range<T>& range) {
    py::dict d;
    d["default"] = default_value;
    d["min"] = range.min;
    d["max"] = range.max;
    return d;
}

template <class T>
py::dict spec(T default_value) {
    py::dict d;
    d["default"] = default_value;
    return d;
}

}  // namespace

void bind_settings(py::module_& m) {
    m.def("settings_spec", [] {
        const visibility::BakeSettings bake;
        const visibility::FitSettings fit;
        const sh::ShadingParameters shading;
        const lights::RigOptions rig;
        const colormap::LookupSpec lookup;
        py::dict s;
        s["threads"] = spec(bake.threads, threads_range);
        s["visibility.rays"] = spec(bake.rays, visibility::BakeSettings::rays_range);
        s["visibility.sh_order"] = spec(bake.order, visibility::BakeSettings::order_range);
        s["visibility.lobes"] = spec(fit.lobes, visibility::FitSettings::lobes_range);
        s["visibility.phong_exponent"] = spec(shading.phong_exponent, sh::ShadingParameters::phong_exponent_range);
        s["visibility.transmission"] = spec(shading.transmission);
        s["lights.count"] = spec(rig.lights.count, lights::LightOptions::count_range);
        s["lights.blue_noise"] = spec(rig.lights.blue_noise);
        s["lights.fit_irradiance"] = spec(rig.lights.fit_irradiance);
        s["lights.filter_brightness"] = spec(rig.filter_brightness);
        s["lights.temporal_filter"] = spec(rig.temporal_filter);
        s["lights.cluster_max"] = spec(rig.cluster_max, lights::RigOptions::cluster_max_range);
        s["lights.adaptive_tolerance"] = spec(rig.adaptive_tolerance, lights::RigOptions::adaptive_tolerance_range);
        s["colormap.lut_width"] = spec(lookup.width, colormap::LookupSpec::size_range);
        s["colormap.lut_height"] = spec(lookup.height, colormap::LookupSpec::size_range);
        s["colormap.sigma_max"] = spec(lookup.sigma_max, colormap::LookupSpec::sigma_max_range);
        s["colormap.mean_min"] = spec(lookup.mean_min);
        s["colormap.mean_max"] = spec(lookup.mean_max);
        return s;
    }, "{name: {'default': value, 'min': ..., 'max': ...}} for every setting the add-on mirrors, from the "
       "core's own settings structs (infinite bounds as inf).");
}

}  // namespace penumbra::bindings
