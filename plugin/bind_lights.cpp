// Bindings for core/lights: light rigs from HDR images, sequences and videos.
// Arrays in and out are numpy; the C++ work runs without the GIL.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>

#include "bindings.hpp"
#include "color/color_config.hpp"
#include "common/error.hpp"
#include "image/frame_source.hpp"
#include "lights/angular_regions.hpp"
#include "lights/clustering.hpp"
#include "lights/environment.hpp"
#include "lights/lights.hpp"
#include "lights/map_reader.hpp"
#include "lights/rig.hpp"
#include "lights/temporal.hpp"
#include "numpy_image.hpp"
#include "progress.hpp"

namespace py = pybind11;

namespace penumbra::bindings {
namespace {

using namespace penumbra::lights;

std::vector<Eigen::Vector3d> to_directions(const py::array& array, const char* what, bool normalize = true) {
    auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(array);
    if (!a || a.ndim() != 2 || a.shape(1) != 3)
        throw ArgumentError(std::string(what) + " must be an (N, 3) array");
    std::vector<Eigen::Vector3d> out(a.shape(0));
    for (py::ssize_t i = 0; i < a.shape(0); ++i) {
        Eigen::Vector3d d(a.at(i, 0), a.at(i, 1), a.at(i, 2));
        if (normalize) {
            if (!d.allFinite() || d.norm() == 0.0)
                throw ArgumentError(std::string(what) + " row " + std::to_string(i) + " is zero or not finite");
            d.normalize();
        }
        out[i] = d;
    }
    return out;
}

py::array_t<double> matrix_to_array(const Eigen::MatrixXd& m) {
    py::array_t<double> out({m.rows(), m.cols()});
    for (Eigen::Index i = 0; i < m.rows(); ++i)
        for (Eigen::Index j = 0; j < m.cols(); ++j) out.mutable_at(i, j) = m(i, j);
    return out;
}

std::vector<Light> to_lights(const py::array& directions, const py::array& rgb) {
    const auto d = to_directions(directions, "directions");
    const auto c = to_directions(rgb, "rgb", false);
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

MapOptions map_options(const std::string& mapping, const std::vector<double>& lens, int max_width, int threads) {
    MapOptions o;
    o.projection = parse_projection(mapping.c_str());
    if (lens.size() > 4) throw ArgumentError("lens takes at most 4 Kannala–Brandt coefficients k1..k4");
    for (std::size_t i = 0; i < lens.size(); ++i) o.lens.k[i] = lens[i];
    o.max_width = max_width;
    o.threads = threads;
    return o;
}

EnvironmentMap map_from_array(const py::array& pixels, const MapOptions& o) {
    Image image = array_to_image(pixels, "pixels");
    py::gil_scoped_release release;
    return make_environment(image, o);
}

class SourceHandle {
public:
    explicit SourceHandle(std::unique_ptr<LightSource> s) : light(std::move(s)), source(&light->frames()) {}
    std::unique_ptr<LightSource> light;
    const FrameSource* source;
};

class PyRigBuilder {
public:
    explicit PyRigBuilder(RigOptions o) : builder(std::move(o)) {}
    RigBuilder builder;
};

}  // namespace

void bind_lights(py::module_& m) {
    // Every default below is the core's own, read from default-constructed options.
    const RigOptions rig;
    const LightOptions& light = rig.lights;
    const MapOptions map;
    const ClusterOptions cluster;
    py::class_<SourceHandle, std::shared_ptr<SourceHandle>>(m, "LightRigSource",
        "Frames of lighting: one image, a numbered sequence or a video (see open_light_source).")
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

    m.def("open_light_source", [](const std::string& path, const std::string& kind) {
        FrameSourceKind k = FrameSourceKind::automatic;
        if (kind == "image") k = FrameSourceKind::single_image;
        else if (kind == "sequence") k = FrameSourceKind::sequence;
        else if (kind == "video") k = FrameSourceKind::video;
        else if (kind != "auto") throw ArgumentError("kind must be 'auto', 'image', 'sequence' or 'video'");
        std::unique_ptr<LightSource> s;
        {
            py::gil_scoped_release release;
            s = std::make_unique<LightSource>(path, k);
        }
        return std::make_shared<SourceHandle>(std::move(s));
    }, py::arg("path"), py::arg("kind") = "auto",
    "Opens an HDR image, the first frame of a numbered sequence (gaps and size changes are errors), or a video.");

    py::class_<PyRigBuilder>(m, "LightRigBuilder",
        "Builds a temporally filtered light rig frame by frame (core/lights/rig.hpp).")
        .def(py::init([](int count, const std::string& sampler, bool blue_noise, const std::string& power,
                         const std::string& mapping, const std::vector<double>& lens, int max_width,
                         bool temporal_filter, double frames_per_second, double pass_hz, double stop_hz,
                         int cluster_max, double cluster_correction, double adaptive_tolerance,
                         py::object world_from_map, int threads) {
            RigOptions o;
            o.map = map_options(mapping, lens, max_width, threads);
            o.lights.count = count;
            o.lights.sampler = parse_sampler(sampler.c_str());
            o.lights.blue_noise = blue_noise;
            o.lights.power = parse_power_mode(power.c_str());
            o.lights.threads = threads;
            o.temporal_filter = temporal_filter;
            o.frames_per_second = frames_per_second;
            o.pass_hz = pass_hz;
            o.stop_hz = stop_hz;
            o.cluster_max = cluster_max;
            o.cluster_correction = cluster_correction;
            o.adaptive_tolerance = adaptive_tolerance;
            if (!world_from_map.is_none()) {
                auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(world_from_map);
                if (!a || a.ndim() != 2 || a.shape(0) != 3 || a.shape(1) != 3)
                    throw ArgumentError("world_from_map must be a 3x3 rotation matrix");
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j) o.world_from_map(i, j) = a.at(i, j);
            }
            return std::make_unique<PyRigBuilder>(o);
        }), py::arg("count") = light.count, py::arg("sampler") = "HAVRAN", py::arg("blue_noise") = light.blue_noise,
            py::arg("power") = "REGION", py::arg("mapping") = "EQUIRECTANGULAR", py::arg("lens") = std::vector<double>{},
            py::arg("max_width") = map.max_width, py::arg("temporal_filter") = rig.temporal_filter, py::arg("frames_per_second") = rig.frames_per_second,
            py::arg("pass_hz") = rig.pass_hz, py::arg("stop_hz") = rig.stop_hz, py::arg("cluster_max") = rig.cluster_max,
            py::arg("cluster_correction") = rig.cluster_correction, py::arg("adaptive_tolerance") = rig.adaptive_tolerance,
            py::arg("world_from_map") = py::none(), py::arg("threads") = map.threads)
        .def("add_frame", [](PyRigBuilder& b, const py::array& pixels) {
            Image image = array_to_image(pixels, "pixels");
            py::gil_scoped_release release;
            b.builder.add_frame(image);
        }, py::arg("pixels"), "Adds one frame of scene-linear radiance (H, W[, C]) in the builder's mapping.")
        .def("add_frame_from", [](PyRigBuilder& b, const SourceHandle& s, int index, py::object config,
                                  const std::string& colorspace) {
            const ColorConfig* c = config.is_none() ? nullptr : config.cast<const ColorConfig*>();
            py::gil_scoped_release release;
            b.builder.add_map(s.light->read_map(index, c, colorspace, b.builder.options().map));
        }, py::arg("source"), py::arg("index"), py::arg("config") = py::none(), py::arg("colorspace") = "",
        "Reads frame `index` of `source`, converts it from `colorspace` to scene-linear with `config` "
        "(no conversion when config is None) and adds it. Image files wider than max_width stream: they are "
        "read band by band and reduced as they arrive, so memory stays bounded (a 16k map never sits whole).")
        .def_property_readonly("frame_count", [](const PyRigBuilder& b) { return b.builder.frame_count(); })
        .def("finish", [](const PyRigBuilder& b, double source_fps) {
            LightRig rig;
            {
                py::gil_scoped_release release;
                rig = b.builder.finish(source_fps);
            }
            const auto f = py::ssize_t(rig.frames.size()), s = py::ssize_t(rig.slots);
            py::array_t<double> dir({f, s, py::ssize_t(3)}), rgb({f, s, py::ssize_t(3)});
            py::array_t<double> power({f, s}), spread({f, s}), total({f, py::ssize_t(3)}), err(f);
            py::array_t<int> active(f);
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
            out["defects"] = defects;
            out["slots"] = rig.slots;
            out["full_sphere"] = rig.full_sphere;
            out["frames_per_second"] = rig.frames_per_second;
            out["filter_taps"] = rig.filter.taps;
            out["cluster_radius"] = rig.cluster_radius;
            return out;
        }, py::arg("source_frames_per_second") = 0.0,
        "Filters, clusters and rotates the lights of every frame added. Returns a dict of arrays: directions "
        "(F, S, 3) towards each light in world coordinates, rgb (F, S, 3) irradiance W/m², power, spread (RMS "
        "angular radius, radians), active, total_rgb, defects, slots, frames_per_second, filter_taps.")
        .def("preview", [](const PyRigBuilder& b, const py::array& directions, const py::array& rgb, int max_width) {
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

    m.def("light_rig_read_map", [](const std::string& path, const std::string& mapping, int max_width,
                                   py::object config, const std::string& colorspace, std::size_t band_bytes,
                                   int threads) {
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
    }, py::arg("path"), py::arg("mapping") = "EQUIRECTANGULAR", py::arg("max_width") = map.max_width,
    py::arg("config") = py::none(), py::arg("colorspace") = "", py::arg("band_bytes") = std::size_t(16) << 20,
    py::arg("threads") = map.threads,
    "The working map of an image file (lights/map_reader.hpp): lat-long files wider than max_width are read band "
    "by band and reduced as they arrive. Dict: pixels (h, w, 3) scene-linear, full_sphere, defects, "
    "source_integral_luminance, streamed, bands, buffer_bytes (largest input buffers held at once).");

    m.def("light_rig_lights", [](const py::array& pixels, const std::string& mapping, int count,
                                 const std::string& sampler, bool blue_noise, const std::string& power,
                                 int max_width, int threads, std::pair<double, double> shift) {
        const MapOptions o = map_options(mapping, {}, max_width, threads);
        const EnvironmentMap map = map_from_array(pixels, o);
        LightOptions lo;
        lo.count = count;
        lo.sampler = parse_sampler(sampler.c_str());
        lo.blue_noise = blue_noise;
        lo.power = parse_power_mode(power.c_str());
        lo.threads = threads;
        lo.point_shift = Eigen::Vector2d(shift.first, shift.second);
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
    }, py::arg("pixels"), py::arg("mapping") = "EQUIRECTANGULAR", py::arg("count") = light.count, py::arg("sampler") = "HAVRAN",
    py::arg("blue_noise") = light.blue_noise, py::arg("power") = "REGION", py::arg("max_width") = map.max_width, py::arg("threads") = map.threads,
    py::arg("shift") = std::pair<double, double>{0.0, 0.0},
    "Lights of one scene-linear environment map (no temporal filtering): dict of directions, rgb, power, spread. "
    "`shift` moves the point set (mod 1); a rig uses (0, 0).");

    m.def("light_rig_exact_irradiance", [](const py::array& pixels, const py::array& normals, const std::string& mapping,
                                           int max_width, int threads) {
        const EnvironmentMap map = map_from_array(pixels, map_options(mapping, {}, max_width, threads));
        const auto n = to_directions(normals, "normals");
        Eigen::MatrixXd e;
        {
            py::gil_scoped_release release;
            e = exact_irradiance(map, n, threads);
        }
        return matrix_to_array(e);
    }, py::arg("pixels"), py::arg("normals"), py::arg("mapping") = "EQUIRECTANGULAR", py::arg("max_width") = 0,
    py::arg("threads") = map.threads, "Irradiance (N, 3) of a diffuse surface for each normal under the whole map.");

    m.def("light_rig_irradiance", [](const py::array& directions, const py::array& rgb, const py::array& normals) {
        const auto lights = to_lights(directions, rgb);
        const auto n = to_directions(normals, "normals");
        return matrix_to_array(irradiance(lights, n));
    }, py::arg("directions"), py::arg("rgb"), py::arg("normals"),
    "Irradiance (N, 3) of directional lights: Σ rgb·max(0, n·d).");

    m.def("light_rig_cluster", [](const py::array& directions, const py::array& rgb, int max_clusters,
                                  double correction, bool full_sphere) {
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
    }, py::arg("directions"), py::arg("rgb"), py::arg("max_clusters"), py::arg("correction") = cluster.correction,
    py::arg("full_sphere") = cluster.full_sphere, "Greedy clustering of lights (paper §4.3).");

    m.def("light_rig_region_table", [](const py::array& directions, int cells_per_face, double lobe_half_angle) {
        const AngularRegionTable t(to_directions(directions, "directions"), cells_per_face, lobe_half_angle);
        std::vector<double> radius(t.region_count());
        for (int r = 0; r < t.region_count(); ++r) radius[r] = t.radius(r);
        py::dict out;
        out["offsets"] = t.offsets();
        out["lights"] = t.items();
        out["radius"] = radius;
        out["cells_per_face"] = t.cells_per_face();
        return out;
    }, py::arg("directions"), py::arg("cells_per_face") = 6, py::arg("lobe_half_angle") = 1.5707963267948966,
    "Angular-region table (paper §4.1) for renderers: CSR offsets and light indices per cube-map region.");

    m.def("light_rig_region_of", [](const py::array& normals, int cells_per_face) {
        const AngularRegionTable t({}, cells_per_face);
        std::vector<int> out;
        for (const auto& n : to_directions(normals, "normals")) out.push_back(t.region_of(n));
        return out;
    }, py::arg("normals"), py::arg("cells_per_face") = 6,
    "Cube-map region index of each direction: (face·g + row)·g + column, faces +x, −x, +y, −y, +z, −z.");

    m.def("light_rig_sample_points", [](int count, bool blue_noise) {
        const auto p = sample_points(count, blue_noise);
        py::array_t<double> out({py::ssize_t(p.size()), py::ssize_t(2)});
        for (std::size_t i = 0; i < p.size(); ++i) {
            out.mutable_at(i, 0) = p[i].x();
            out.mutable_at(i, 1) = p[i].y();
        }
        return out;
    }, py::arg("count"), py::arg("blue_noise") = light.blue_noise, "Halton (2, 3) points from index 1, optionally Lloyd-relaxed.");

    m.def("light_rig_filter", [](double frames_per_second, double pass_hz, double stop_hz, int taps) {
        if (taps > 0) return design_lowpass(frames_per_second, pass_hz, stop_hz, taps).taps;
        return filter_for_rate(frames_per_second, pass_hz, stop_hz).taps;
    }, py::arg("frames_per_second") = paper_rate_hz, py::arg("pass_hz") = paper_pass_hz,
    py::arg("stop_hz") = paper_stop_hz, py::arg("taps") = 0,
    "The temporal FIR taps used at a frame rate (the paper's at 21 Hz), or a Remez design with `taps` taps.");

    m.def("rotate_equirectangular_z", [](const py::array& pixels, double angle) {
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

}  // namespace penumbra::bindings
