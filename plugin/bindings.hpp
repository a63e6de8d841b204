// Registration functions, one per area of the core, each defined in its own
// plugin/bind_<area>.cpp and called from module.cpp.
#pragma once

#include <pybind11/pybind11.h>

namespace penumbra::bindings {

void bind_image(pybind11::module_& m);
void bind_color(pybind11::module_& m);
void bind_sh(pybind11::module_& m);            // basis, zonal, rotation, projection
void bind_sh_operators(pybind11::module_& m);  // 1D-BRDF convolution operators
void bind_shading(pybind11::module_& m);       // batched pose shading
void bind_visibility(pybind11::module_& m);    // visibility baker
void bind_lights(pybind11::module_& m);        // light rigs
void bind_colormap(pybind11::module_& m);      // colour-map lookups
void bind_settings(pybind11::module_& m);      // settings_spec: the core's defaults and ranges
void bind_testing(pybind11::module_& m);       // _penumbra.testing: hooks for tests

}  // namespace penumbra::bindings
