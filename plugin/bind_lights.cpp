// _penumbra.lights: light rigs from HDR images, sequences and videos
// (core/lights). This file holds the enums, light sources and the functions
// on one frame; the temporally filtered rig builder is in bind_lights_rig.cpp.
// Arrays in and out are numpy; the C++ work runs without the GIL.
#include "bind_lights.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <string>

#include "arrays.hpp"
#include "bindings.hpp"
#include "color/color_config.hpp"
#include "common/error.hpp"
#include "enums.hpp"
#include "image/frame_source.hpp"
#include "lights/clustering.hpp"
#include "lights/rig.hpp"
#include "lights/sampling.hpp"
#include "lights/sun_irradiance.hpp"
#include "lights/temporal.hpp"
#include "lights/tracking.hpp"
#include "numpy_image.hpp"

namespace py = pybind11;

namespace penumbra::bindings {

using namespace penumbra::lights;

MapOptions map_options(Projection mapping, const std::vector<double>& lens, int max_width, int threads) {
    MapOptions o;
    o.projection = mapping;
    if (lens.size() > 4) throw ArgumentError("lens takes at most 4 Kannala–Brandt coefficients k1..k4");
    for (std::size_t i = 0; i < lens.size(); ++i) o.lens.k[i] = lens[i];
    o.max_width = max_width;
    o.threads = threads;
    return o;
}

std::vector<Light> to_lights(const py::array& directions, const py::array& rgb) {
    const auto d = vectors3(directions, "directions", true);
    const auto c = vectors3(rgb, "rgb", false);
    if (d.size() != c.size()) throw ArgumentError("directions and rgb need the same number of rows");
    std::vector<Light> lights(d.size());
    for (std::size_t i = 0; i < d.size(); ++i) {
        lights[i].index = int(i);
        lights[i].direction = d[i];
        lights[i].rgb = c[i];
        lights[i].power = rec709_luminance[0] * c[i][0] + rec709_luminance[1] * c[i][1] + rec709_luminance[2] * c[i][2];
    }
    return lights;
}

py::dict defects_dict(const PixelDefects& d) {
    py::dict out;
    out["nan"] = d.nan;
    out["inf"] = d.inf;
    out["negative"] = d.negative;
    return out;
}

namespace {

py::dict lights_dict(const std::vector<Light>& lights) {
    const auto n = py::ssize_t(lights.size());
    py::array_t<double> dir({n, py::ssize_t(3)}), rgb({n, py::ssize_t(3)}), sample({n, py::ssize_t(3)});
    py::array_t<double> power(n), spread(n);
    for (py::ssize_t i = 0; i < n; ++i) {
        for (int c = 0; c < 3; ++c) {
            dir.mutable_at(i, c) = lights[i].direction[c];
            rgb.mutable_at(i, c) = lights[i].rgb[c];
            sample.mutable_at(i, c) = lights[i].sample_direction[c];
        }
        power.mutable_at(i) = lights[i].power;
        spread.mutable_at(i) = lights[i].spread;
    }
    py::dict out;
    out["directions"] = dir;
    out["rgb"] = rgb;
    out["power"] = power;
    out["spread"] = spread;
    out["sample_directions"] = sample;
    return out;
}

EnvironmentMap map_from_array(const py::array& pixels, const MapOptions& o) {
    Image image = array_to_image(pixels, "pixels");
    py::gil_scoped_release release;
    return make_environment(image, o);
}

void bind_enums(py::module_& m) {
    bind_enum<Projection>(m, "Projection", "mapping",
        {{"EQUIRECTANGULAR", Projection::equirectangular}, {"HEMISPHERE_POLAR", Projection::hemisphere_polar},
         {"FISHEYE", Projection::fisheye}, {"MIRROR_BALL", Projection::mirror_ball}},
        "How an environment image maps to directions (core/lights/mapping.hpp): EQUIRECTANGULAR (Blender's "
        "World), HEMISPHERE_POLAR (the upper half of one), FISHEYE (looking up), MIRROR_BALL.");
    bind_enum<SamplerKind>(m, "Sampler", "sampler",
        {{"HAVRAN", SamplerKind::havran}, {"STANDARD", SamplerKind::standard}},
        "How sample points become directions: HAVRAN (continuous, smooth light motion) or STANDARD "
        "(marginal/conditional inversion of the image).");
    bind_enum<PowerMode>(m, "Power", "power",
        {{"REGION", PowerMode::region}, {"EQUAL", PowerMode::equal}},
        "What each light carries: REGION (the power and colour of its region of the map) or EQUAL (the paper's "
        "equal powers).");
    bind_enum<Tracking>(m, "Tracking", "tracking",
        {{"FOLLOW", Tracking::follow}, {"RESAMPLE", Tracking::resample}},
        "How lights carry over between frames (core/lights/tracking.hpp): FOLLOW (turned with the map's motion "
        "and refitted, identities kept) or RESAMPLE (the paper's: light k = point k through each frame's CDF).");
    bind_enum<SunModel>(m, "SunModel", "sun_model",
        {{"POINT", SunModel::point}, {"BLENDER3_DISC", SunModel::blender3_disc},
         {"BLENDER4_CONE", SunModel::blender4_cone}, {"EEVEE_NEXT_SHADOWED", SunModel::eevee_next_shadowed},
         {"EEVEE_LEGACY", SunModel::eevee_legacy}},
        "How a renderer spreads a sun's flux over its angle (core/lights/sun_irradiance.hpp): BLENDER3_DISC "
        "(Cycles in Blender 3.x), BLENDER4_CONE (Cycles 4.0 and later), EEVEE_NEXT_SHADOWED (EEVEE Next's "
        "shadowed sun: the cone, its shadow cut at the receiver's horizon), EEVEE_LEGACY (3.x: the cone, "
        "another power), POINT (angle 0).");
}

py::dict read_map(const std::string& path, Projection mapping, int max_width, py::object config,
                  const std::string& colorspace, std::size_t band_bytes, int threads) {
    const ColorConfig* c = config.is_none() ? nullptr : config.cast<const ColorConfig*>();
    const MapOptions o = map_options(mapping, {}, max_width, threads);
    EnvironmentMap map;
    ReadReport report;
    {
        py::gil_scoped_release release;
        map = read_environment(path, c, colorspace, o, {}, band_bytes, &report);
    }
    Image image(map.width, map.height, 3);
    image.pixels = std::move(map.rgb);
    py::dict out;
    out["pixels"] = image_to_array(std::move(image));
    out["full_sphere"] = map.full_sphere;
    out["defects"] = defects_dict(map.defects);
    out["source_integral_luminance"] = map.source_integral_luminance;
    out["streamed"] = report.streamed;
    out["bands"] = report.bands;
    out["buffer_bytes"] = report.buffer_bytes;
    return out;
}

void bind_sources(py::module_& m) {
    const MapOptions map;  // every default below is the core's own
    py::class_<SourceHandle, std::shared_ptr<SourceHandle>>(m, "Source",
        "Frames of lighting: one image, a numbered sequence or a video (see open_source).")
        .def_property_readonly("frame_count", [](const SourceHandle& s) { return s.source->frame_count(); })
        .def_property_readonly("width", [](const SourceHandle& s) { return s.source->width(); })
        .def_property_readonly("height", [](const SourceHandle& s) { return s.source->height(); })
        .def_property_readonly("frames_per_second", [](const SourceHandle& s) { return s.source->frames_per_second(); })
        .def("describe", [](const SourceHandle& s) { return s.source->describe(); })
        .def("read", [](const SourceHandle& s, int index) {
            Image image;
            {
                py::gil_scoped_release release;
                image = s.source->read(index);
            }
            return image_to_array(std::move(image));
        }, py::arg("index"), "Frame `index` as float32 (H, W, 3), as stored.");

    m.def("open_source", [](const std::string& path, FrameSourceKind kind) {
        std::unique_ptr<LightSource> s;
        {
            py::gil_scoped_release release;
            s = std::make_unique<LightSource>(path, kind);
        }
        return std::make_shared<SourceHandle>(std::move(s));
    }, py::arg("path"), py::arg("kind") = FrameSourceKind::automatic,
    "Opens an HDR image, the first frame of a numbered sequence (gaps and size changes are errors), or a video.");

    m.def("read_map", &read_map, py::arg("path"), py::arg("mapping") = map.projection,
          py::arg("max_width") = map.max_width, py::arg("config") = py::none(), py::arg("colorspace") = "",
          py::arg("band_bytes") = std::size_t(16) << 20, py::arg("threads") = map.threads,
    "The working map of an image file (lights/map_reader.hpp): files wider than max_width are read band by band "
    "(lat-long: reduced as the rows arrive; fisheye, mirror ball: each band's look-ups taken). Dict: pixels (h, w, 3) scene-linear, full_sphere, defects, "
    "source_integral_luminance, streamed, bands, buffer_bytes (largest input buffers held at once).");
}

py::dict frame_lights(const py::array& pixels, Projection mapping, int count, SamplerKind sampler, bool blue_noise,
                      PowerMode power, int max_width, int threads, std::pair<double, double> shift,
                      bool fit_irradiance, SunModel sun_model) {
    const EnvironmentMap map = map_from_array(pixels, map_options(mapping, {}, max_width, threads));
    LightOptions lo;
    lo.count = count;
    lo.sampler = sampler;
    lo.blue_noise = blue_noise;
    lo.power = power;
    lo.threads = threads;
    lo.point_shift = Eigen::Vector2d(shift.first, shift.second);
    lo.fit_irradiance = fit_irradiance;
    lo.sun_model = sun_model;
    FrameLights f;
    {
        py::gil_scoped_release release;
        f = compute_lights(map, lo);
    }
    py::dict out = lights_dict(f.lights);
    out["total_rgb"] = std::vector<double>{f.total_rgb[0], f.total_rgb[1], f.total_rgb[2]};
    out["total_power"] = f.total_power;
    out["defects"] = defects_dict(map.defects);
    out["working_size"] = py::make_tuple(map.width, map.height);
    return out;
}

py::array_t<double> exact_irradiance_of(const py::array& pixels, const py::array& normals, Projection mapping,
                                        int max_width, int threads) {
    const EnvironmentMap map = map_from_array(pixels, map_options(mapping, {}, max_width, threads));
    const auto n = vectors3(normals, "normals", true);
    Eigen::MatrixXd e;
    {
        py::gil_scoped_release release;
        e = exact_irradiance(map, n, threads);
    }
    return matrix_to_array(e);
}

py::dict cluster(const py::array& directions, const py::array& rgb, int max_clusters, double correction,
                 bool full_sphere) {
    const auto lights = to_lights(directions, rgb);
    ClusterOptions o;
    o.max_clusters = max_clusters;
    o.correction = correction;
    o.full_sphere = full_sphere;
    const Clustering c = cluster_lights(lights, o);
    py::dict out = lights_dict(c.clusters);
    std::vector<int> index;
    for (const auto& l : c.clusters) index.push_back(l.index);
    out["index"] = index;
    out["cluster_of"] = c.cluster_of;
    out["radius"] = c.radius;
    return out;
}

void bind_frame_functions(py::module_& m) {
    const LightOptions light;  // every default below is the core's own
    const MapOptions map;
    const ClusterOptions clustering;
    m.def("frame_lights", &frame_lights, py::arg("pixels"), py::arg("mapping") = map.projection,
          py::arg("count") = light.count, py::arg("sampler") = light.sampler, py::arg("blue_noise") = light.blue_noise,
          py::arg("power") = light.power, py::arg("max_width") = map.max_width, py::arg("threads") = map.threads,
          py::arg("shift") = std::pair<double, double>{0.0, 0.0}, py::arg("fit_irradiance") = light.fit_irradiance,
          py::arg("sun_model") = light.sun_model,
    "Lights of one scene-linear environment map (no temporal filtering): dict of directions, rgb, power, spread. "
    "`shift` moves the point set (mod 1); a rig uses (0, 0). `fit_irradiance` refits colours and directions so "
    "the suns (drawn as `sun_model`) match the map's irradiance (core/lights/irradiance_fit.hpp).");

    m.def("exact_irradiance", &exact_irradiance_of, py::arg("pixels"), py::arg("normals"),
          py::arg("mapping") = map.projection, py::arg("max_width") = 0, py::arg("threads") = map.threads,
          "Irradiance (N, 3) of a diffuse surface for each normal under the whole map.");

    m.def("irradiance", [](const py::array& directions, const py::array& rgb, const py::array& normals,
                           py::object spread, SunModel sun_model) {
        auto lights = to_lights(directions, rgb);
        const auto n = vectors3(normals, "normals", true);
        if (spread.is_none()) return matrix_to_array(irradiance(lights, n));
        const auto s = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(spread);
        if (!s || s.ndim() != 1 || std::size_t(s.shape(0)) != lights.size())
            throw ArgumentError("spread must be a 1-D array with one value per light");
        for (std::size_t k = 0; k < lights.size(); ++k) lights[k].spread = s.at(py::ssize_t(k));
        return matrix_to_array(sun_irradiance(lights, n, sun_model));
    }, py::arg("directions"), py::arg("rgb"), py::arg("normals"), py::arg("spread") = py::none(),
    py::arg("sun_model") = SunModel::blender4_cone,
    "Irradiance (N, 3) of directional lights: Σ rgb·max(0, n·d); with `spread` (RMS region radius per light), "
    "of the suns the add-on writes, drawn as `sun_model` (core/lights/sun_irradiance.hpp).");

    m.def("cluster", &cluster, py::arg("directions"), py::arg("rgb"), py::arg("max_clusters"),
          py::arg("correction") = clustering.correction, py::arg("full_sphere") = clustering.full_sphere,
          "Greedy clustering of lights (paper §4.3).");

    m.def("temporal_filter", [](double frames_per_second, double pass_hz, double stop_hz, int taps) {
        if (taps > 0) return design_lowpass(frames_per_second, pass_hz, stop_hz, taps).taps;
        return filter_for_rate(frames_per_second, pass_hz, stop_hz).taps;
    }, py::arg("frames_per_second") = paper_rate_hz, py::arg("pass_hz") = paper_pass_hz,
    py::arg("stop_hz") = paper_stop_hz, py::arg("taps") = 0,
    "The temporal FIR taps used at a frame rate (the paper's at 21 Hz), or a Remez design with `taps` taps.");

    m.def("rotate_map_z", [](const py::array& pixels, double angle) {
        Image image = array_to_image(pixels, "pixels");
        Image out;
        {
            py::gil_scoped_release release;
            out = rotate_equirectangular_z(image, angle);
        }
        return image_to_array(std::move(out));
    }, py::arg("pixels"), py::arg("angle"),
    "Rotates an equirectangular image about +z by `angle` radians (content at d moves to Rz·d).");
}

void bind_suns(py::module_& m) {
    m.attr("MIN_SUN_ANGLE") = min_sun_angle;
    m.def("sun_model_for_blender", &sun_model_for_blender, py::arg("major"), py::arg("minor"),
          "The SunModel Cycles draws suns with in Blender major.minor (BLENDER4_CONE from 4.0 on).");
    m.def("sun_model_for_renderer", &sun_model_for_renderer, py::arg("major"), py::arg("minor"),
          py::arg("eevee"), py::arg("shadow"),
          "The SunModel a target renderer draws a sun with: Cycles (eevee False) as sun_model_for_blender; "
          "EEVEE_LEGACY before 4.2; EEVEE Next: EEVEE_NEXT_SHADOWED for a sun casting a shadow, else BLENDER4_CONE.");
    m.def("cone_fraction_above_horizon", [](const Doubles& c, double half_angle) {
        return map_elements(c, [half_angle](double v) { return cone_fraction_above_horizon(v, half_angle); });
    }, py::arg("cos_angle"), py::arg("half_angle"),
    "Fraction of a uniform cone of `half_angle` (radians), its axis at cos β = `cos_angle` (any shape) from a "
    "receiver's normal, above the receiver's horizon: what EEVEE Next's sun shadow keeps on an open receiver.");
    m.def("sun_angle", [](const Doubles& spread) { return map_elements(spread, sun_angle); }, py::arg("spread"),
          "Angle (radians, full) of the sun written for each RMS angular radius in `spread` (any shape): "
          "clip(2√2·spread, 0, π), 0 below MIN_SUN_ANGLE.");
    m.def("sun_strength_per_flux", [](const Doubles& angle, SunModel sun_model) {
        return map_elements(angle, [sun_model](double a) { return sun_strength_per_flux(a, sun_model); });
    }, py::arg("angle"), py::arg("sun_model"),
    "Sun strength per unit of the light's flux ∫L dω for each sun angle (any shape) drawn as `sun_model`: "
    "(1 + cos(angle/2))/2 for BLENDER4_CONE and EEVEE_NEXT_SHADOWED, r²/((2 + r²)(1 − cos(angle/2))) "
    "with r = tan(angle/2) for EEVEE_LEGACY, 1 otherwise.");
}

}  // namespace

void bind_lights(py::module_& m) {
    bind_enums(m);
    bind_sources(m);
    bind_lights_rig(m);
    bind_frame_functions(m);
    bind_suns(m);
}

}  // namespace penumbra::bindings
