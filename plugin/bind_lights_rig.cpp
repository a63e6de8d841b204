// _penumbra.lights.RigBuilder: a temporally filtered light rig built frame by
// frame (core/lights/rig.hpp).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <string>
#include <vector>

#include "arrays.hpp"
#include "bind_lights.hpp"
#include "bindings.hpp"
#include "color/color_config.hpp"
#include "common/error.hpp"
#include "lights/rig.hpp"
#include "numpy_image.hpp"

namespace py = pybind11;

namespace penumbra::bindings {

namespace {

using namespace penumbra::lights;

// Holds the core's builder; pybind11 needs a movable handle.
class PyRigBuilder {
public:
    explicit PyRigBuilder(RigOptions o) : builder(std::move(o)) {}
    RigBuilder builder;
};

std::unique_ptr<PyRigBuilder> make_builder(int count, SamplerKind sampler, bool blue_noise, PowerMode power,
                                           Projection mapping, const std::vector<double>& lens, int max_width,
                                           bool temporal_filter, double frames_per_second, double pass_hz,
                                           double stop_hz, int cluster_max, double cluster_correction,
                                           double adaptive_tolerance, py::object world_from_map, int threads,
                                           bool fit_irradiance, SunModel sun_model, Tracking tracking,
                                           bool filter_brightness) {
    RigOptions o;
    o.map = map_options(mapping, lens, max_width, threads);
    o.lights.count = count;
    o.lights.sampler = sampler;
    o.lights.blue_noise = blue_noise;
    o.lights.power = power;
    o.lights.threads = threads;
    o.lights.fit_irradiance = fit_irradiance;
    o.lights.sun_model = sun_model;
    o.temporal_filter = temporal_filter;
    o.tracking = tracking;
    o.filter_brightness = filter_brightness;
    o.frames_per_second = frames_per_second;
    o.pass_hz = pass_hz;
    o.stop_hz = stop_hz;
    o.cluster_max = cluster_max;
    o.cluster_correction = cluster_correction;
    o.adaptive_tolerance = adaptive_tolerance;
    if (!world_from_map.is_none()) o.world_from_map = matrix3(world_from_map, "world_from_map");
    return std::make_unique<PyRigBuilder>(o);
}

// The rig as a dict of arrays, one row per frame.
py::dict rig_dict(const LightRig& rig) {
    const auto f = py::ssize_t(rig.frames.size()), s = py::ssize_t(rig.slots);
    py::array_t<double> dir({f, s, py::ssize_t(3)}), rgb({f, s, py::ssize_t(3)});
    py::array_t<double> power({f, s}), spread({f, s}), total({f, py::ssize_t(3)}), err(f);
    py::array_t<int> active(f), counts(f);
    py::list defects;
    for (py::ssize_t t = 0; t < f; ++t) {
        const RigFrame& fr = rig.frames[t];
        for (py::ssize_t k = 0; k < s; ++k) {
            const Light& l = fr.lights[k];
            for (int c = 0; c < 3; ++c) {
                dir.mutable_at(t, k, c) = l.direction[c];
                rgb.mutable_at(t, k, c) = l.rgb[c];
            }
            power.mutable_at(t, k) = l.power;
            spread.mutable_at(t, k) = l.spread;
        }
        for (int c = 0; c < 3; ++c) total.mutable_at(t, c) = fr.total_rgb[c];
        active.mutable_at(t) = fr.active;
        err.mutable_at(t) = fr.adaptive_error;
        counts.mutable_at(t) = fr.adaptive_count;
        defects.append(defects_dict(fr.defects));
    }
    py::dict out;
    out["directions"] = dir;
    out["rgb"] = rgb;
    out["power"] = power;
    out["spread"] = spread;
    out["total_rgb"] = total;
    out["active"] = active;
    out["adaptive_error"] = err;
    out["adaptive_counts"] = counts;
    out["adaptive_count"] = rig.adaptive_count;
    out["defects"] = defects;
    out["slots"] = rig.slots;
    out["full_sphere"] = rig.full_sphere;
    out["frames_per_second"] = rig.frames_per_second;
    out["filter_taps"] = rig.filter.taps;
    out["cluster_radius"] = rig.cluster_radius;
    return out;
}

void bind_frames_in(py::class_<PyRigBuilder>& c) {
    c.def("add_frame", [](PyRigBuilder& b, const py::array& pixels) {
        Image image = array_to_image(pixels, "pixels");
        py::gil_scoped_release release;
        b.builder.add_frame(image);
    }, py::arg("pixels"), "Adds one frame of scene-linear radiance (H, W[, C]) in the builder's mapping.");
    c.def("add_frame_from", [](PyRigBuilder& b, const SourceHandle& s, int index, py::object config,
                               const std::string& colorspace) {
        const ColorConfig* c = config.is_none() ? nullptr : config.cast<const ColorConfig*>();
        py::gil_scoped_release release;
        b.builder.add_map(s.light->read_map(index, c, colorspace, b.builder.options().map));
    }, py::arg("source"), py::arg("index"), py::arg("config") = py::none(), py::arg("colorspace") = "",
    "Reads frame `index` of `source`, converts it from `colorspace` to scene-linear with `config` "
    "(no conversion when config is None) and adds it. Image files wider than max_width stream: they are "
    "read band by band and reduced as they arrive, so memory stays bounded (a 16k map never sits whole).");
    c.def_property_readonly("frame_count", [](const PyRigBuilder& b) { return b.builder.frame_count(); });
}

void bind_results_out(py::class_<PyRigBuilder>& c) {
    c.def("finish", [](const PyRigBuilder& b, double source_fps) {
        LightRig rig;
        {
            py::gil_scoped_release release;
            rig = b.builder.finish(source_fps);
        }
        return rig_dict(rig);
    }, py::arg("source_frames_per_second") = 0.0,
    "Filters, clusters and rotates the lights of every frame added. Returns a dict of arrays: directions "
    "(F, S, 3) towards each light in world coordinates, rgb (F, S, 3) irradiance W/m², power, spread (RMS "
    "angular radius, radians), active, total_rgb, defects, slots, frames_per_second, filter_taps.");
    c.def("preview", [](const PyRigBuilder& b, const py::array& directions, const py::array& rgb, int max_width) {
        const auto lights = to_lights(directions, rgb);
        Image image;
        {
            py::gil_scoped_release release;
            if (b.builder.frame_count() == 0) throw ArgumentError("add a frame before asking for a preview");
            image = preview_image(b.builder.last_map(), lights, b.builder.options().world_from_map, max_width);
        }
        return image_to_array(std::move(image));
    }, py::arg("directions"), py::arg("rgb"), py::arg("max_width") = 512,
    "The last frame's map (tone-compressed to [0, 1), scene-linear) with a green ring per light.");
}

}  // namespace

void bind_lights_rig(py::module_& m) {
    // Every default below is the core's own, read from default-constructed options.
    const RigOptions rig;
    const LightOptions& light = rig.lights;
    const MapOptions& map = rig.map;
    py::class_<PyRigBuilder> c(m, "RigBuilder", "Builds a temporally filtered light rig frame by frame "
                                                "(core/lights/rig.hpp).");
    c.def(py::init(&make_builder), py::arg("count") = light.count, py::arg("sampler") = light.sampler,
          py::arg("blue_noise") = light.blue_noise, py::arg("power") = light.power,
          py::arg("mapping") = map.projection, py::arg("lens") = std::vector<double>{},
          py::arg("max_width") = map.max_width, py::arg("temporal_filter") = rig.temporal_filter,
          py::arg("frames_per_second") = rig.frames_per_second, py::arg("pass_hz") = rig.pass_hz,
          py::arg("stop_hz") = rig.stop_hz, py::arg("cluster_max") = rig.cluster_max,
          py::arg("cluster_correction") = rig.cluster_correction,
          py::arg("adaptive_tolerance") = rig.adaptive_tolerance, py::arg("world_from_map") = py::none(),
          py::arg("threads") = map.threads, py::arg("fit_irradiance") = light.fit_irradiance,
          py::arg("sun_model") = light.sun_model, py::arg("tracking") = rig.tracking,
          py::arg("filter_brightness") = rig.filter_brightness);
    bind_frames_in(c);
    bind_results_out(c);
}

}  // namespace penumbra::bindings
