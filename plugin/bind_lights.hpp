// What bind_lights.cpp and bind_lights_rig.cpp share: the handle of an open
// light source and the conversions between numpy and core/lights types.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <vector>

#include "image/image.hpp"
#include "lights/environment.hpp"
#include "lights/frame_lights.hpp"
#include "lights/map_reader.hpp"

namespace penumbra::bindings {

// _penumbra.lights.Source: frames of lighting, kept open between reads.
class SourceHandle {
public:
    explicit SourceHandle(std::unique_ptr<lights::LightSource> s) : light(std::move(s)), source(&light->frames()) {}
    std::unique_ptr<lights::LightSource> light;
    const FrameSource* source;
};

// Map options from a binding's arguments; lens: at most 4 Kannala–Brandt coefficients.
lights::MapOptions map_options(lights::Projection mapping, const std::vector<double>& lens, int max_width,
                               int threads);

// Directional lights from (N, 3) directions (normalized here) and RGB; power is the Rec. 709 luminance.
std::vector<lights::Light> to_lights(const pybind11::array& directions, const pybind11::array& rgb);

pybind11::dict defects_dict(const PixelDefects& d);

}  // namespace penumbra::bindings
