// Registration functions, one per submodule of _penumbra (module.cpp makes
// the submodules and calls them), each defined in plugin/bind_<tool>*.cpp.
// A submodule's enums are registered first, then its classes, then its
// functions, so every signature names Python types.
#pragma once

#include <pybind11/pybind11.h>

namespace penumbra::bindings {

void bind_image(pybind11::module_& image);  // image and video I/O, frame sources; calls the one below
void bind_image_environment(pybind11::module_& image);  // Environment Textures looked up, the World resampled
void bind_color(pybind11::module_& color);  // OpenColorIO configs

void bind_sh(pybind11::module_& sh);            // basis, zonal, rotation, projection
void bind_sh_operators(pybind11::module_& sh);  // 1D-BRDF convolution operators
void bind_sh_shading(pybind11::module_& sh);    // batched pose shading

void bind_visibility(pybind11::module_& visibility);           // enums, mesh helpers, ZH lobes; calls the two below
void bind_visibility_training(pybind11::module_& visibility);  // TrainingSet: baking frames
void bind_visibility_model(pybind11::module_& visibility);     // PoseModel and fit_model

void bind_lights(pybind11::module_& lights);      // enums, sources, one-frame functions; calls the one below
void bind_lights_rig(pybind11::module_& lights);  // RigBuilder

void bind_colormap(pybind11::module_& colormap);  // colour-map lookups, ColorRamps, microsurface statistics

void bind_settings(pybind11::module_& m);       // settings_spec: the core's defaults and ranges (top level)
void bind_files(pybind11::module_& m);          // durable file writes for the add-on (top level)
void bind_testing(pybind11::module_& testing);  // hooks for tests and benchmarks

}  // namespace penumbra::bindings
