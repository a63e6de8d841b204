// _penumbra.colormap: colour maps and ColorRamps, the exact
// Gaussian-filtered lookup (paper Sec. 4.2) and the microsurface statistics
// (paper Sec. 5). numpy in and out; the GIL is released while tables build.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <string>

#include "arrays.hpp"
#include "bindings.hpp"
#include "colormap/color_map.hpp"
#include "colormap/color_ramp.hpp"
#include "colormap/lookup.hpp"
#include "colormap/microsurface.hpp"
#include "common/error.hpp"
#include "enums.hpp"
#include "numpy_image.hpp"
#include "progress.hpp"

namespace py = pybind11;

namespace penumbra::bindings {

namespace {

using namespace penumbra::colormap;

// The two ways to each microsurface statistic the core offers, chosen by
// name: the core has a function each, not an enum.
enum class HeightMethod { exact, fit };
enum class SlopeMethod { gaussian, numerical };

void bind_enums(py::module_& m) {
    bind_enum<SigmaSpacing>(m, "SigmaSpacing", "sigma_spacing",
        {{"LINEAR", SigmaSpacing::linear}, {"QUADRATIC", SigmaSpacing::quadratic}},
        "Rows of a lookup: LINEAR (sigma = sigma_max t) or QUADRATIC (sigma = sigma_max t², rows packed near 0).");
    bind_enum<MapInterpolation>(m, "MapInterpolation", "interpolation",
        {{"LINEAR", MapInterpolation::linear}, {"CONSTANT", MapInterpolation::constant}},
        "How a colour map joins its knots: LINEAR, or CONSTANT (each knot's colour held up to the next).");
    bind_enum<RampInterpolation>(m, "RampInterpolation", "interpolation",
        {{"LINEAR", RampInterpolation::linear}, {"EASE", RampInterpolation::ease},
         {"CARDINAL", RampInterpolation::cardinal}, {"B_SPLINE", RampInterpolation::b_spline},
         {"CONSTANT", RampInterpolation::constant}},
        "A ColorRamp's interpolation, Blender's ColorRamp.interpolation.");
    bind_enum<RampColorMode>(m, "RampColorMode", "color_mode",
        {{"RGB", RampColorMode::rgb}, {"HSV", RampColorMode::hsv}, {"HSL", RampColorMode::hsl}},
        "A ColorRamp's colour mode, Blender's ColorRamp.color_mode.");
    bind_enum<RampHueInterpolation>(m, "RampHueInterpolation", "hue_interpolation",
        {{"NEAR", RampHueInterpolation::near}, {"FAR", RampHueInterpolation::far},
         {"CW", RampHueInterpolation::cw}, {"CCW", RampHueInterpolation::ccw}},
        "A ColorRamp's hue interpolation (HSV, HSL), Blender's ColorRamp.hue_interpolation.");
    bind_enum<RampSampling>(m, "RampSampling", "sampling",
        {{"CYCLES", RampSampling::cycles_table}, {"EXACT", RampSampling::exact}},
        "How a ColorRamp becomes knots: CYCLES (the 256-entry table Cycles renders with) or EXACT (Blender's own "
        "evaluation: the stops where piecewise linear/constant, else dense samples).");
    bind_enum<HeightMethod>(m, "EffectiveHeightMethod", "method",
        {{"EXACT", HeightMethod::exact}, {"FIT", HeightMethod::fit}},
        "EXACT (numerical, in log space) or FIT (paper Eqs. 17-18).");
    bind_enum<SlopeMethod>(m, "SlopeFilteringMethod", "method",
        {{"GAUSSIAN", SlopeMethod::gaussian}, {"NUMERICAL", SlopeMethod::numerical}},
        "GAUSSIAN (closed form) or NUMERICAL (a grid over the slope plane).");
}

ColorRamp make_ramp(const py::array& stops_array, RampInterpolation interpolation, RampColorMode color_mode,
                    RampHueInterpolation hue) {
    auto stops = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(stops_array);
    if (!stops || stops.ndim() != 2 || stops.shape(1) != 5)
        throw ArgumentError("stops must be an array of shape (count, 5): position, red, green, blue, alpha");
    ColorRamp ramp;
    ramp.interpolation = interpolation;
    ramp.color_mode = color_mode;
    ramp.hue_interpolation = hue;
    for (py::ssize_t i = 0; i < stops.shape(0); ++i)
        ramp.stops.push_back({stops.at(i, 0), {stops.at(i, 1), stops.at(i, 2), stops.at(i, 3), stops.at(i, 4)}});
    validate_ramp(ramp);
    return ramp;
}

ColorMap map_from_samples(const py::array& colors_array) {
    auto colors = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(colors_array);
    if (!colors || (colors.ndim() != 1 && colors.ndim() != 2))
        throw ArgumentError("colors must be an array of shape (count, channels)");
    const int count = static_cast<int>(colors.shape(0));
    const int channels = colors.ndim() == 2 ? static_cast<int>(colors.shape(1)) : 1;
    return color_map_from_samples(colors.data(), count, channels);
}

ColorMap map_from_knots(const py::array& positions_array, const py::array& colors_array, MapInterpolation interp) {
    auto positions = Doubles::ensure(positions_array);
    auto colors = Doubles::ensure(colors_array);
    if (!positions || positions.ndim() != 1 || !colors || colors.ndim() != 2 || colors.shape(0) != positions.shape(0))
        throw ArgumentError("knots: positions (K,) and colors (K, channels) are needed");
    std::vector<double> p(positions.data(), positions.data() + positions.size());
    std::vector<double> c(colors.data(), colors.data() + colors.size());
    return color_map_from_knots(std::move(p), std::move(c), static_cast<int>(colors.shape(1)), interp);
}

py::array_t<float> build_table(const ColorMap& map, const LookupSpec& spec, py::object progress) {
    PyProgress py_progress(std::move(progress));
    Image table;
    try {
        py::gil_scoped_release release;
        table = build_lookup(map, spec, py_progress.progress());
    } catch (const Cancelled&) {
        py_progress.rethrow_if_failed();
        throw;
    }
    return image_to_array(std::move(table));
}

LookupSpec make_spec(int width, int height, double sigma_max, double mean_min, double mean_max, SigmaSpacing spacing) {
    LookupSpec spec{width, height, sigma_max, mean_min, mean_max, spacing};
    spec.validate();
    return spec;
}

py::dict accuracy_dict(const LookupAccuracy& a) {
    py::dict d;
    d["max_abs_error"] = a.max_abs_error;
    d["rms_error"] = a.rms_error;
    d["worst_mean"] = a.worst_mean;
    d["worst_sigma"] = a.worst_sigma;
    return d;
}

py::array_t<float> lut(const py::array& colors, int width, int height, double sigma_max, double mean_min,
                       double mean_max, SigmaSpacing sigma_spacing, py::object progress) {
    const ColorMap map = map_from_samples(colors);
    return build_table(map, make_spec(width, height, sigma_max, mean_min, mean_max, sigma_spacing),
                       std::move(progress));
}

py::array_t<float> lut_knots(const py::array& positions, const py::array& colors, MapInterpolation interpolation,
                             int width, int height, double sigma_max, double mean_min, double mean_max,
                             SigmaSpacing sigma_spacing, py::object progress) {
    const ColorMap map = map_from_knots(positions, colors, interpolation);
    return build_table(map, make_spec(width, height, sigma_max, mean_min, mean_max, sigma_spacing),
                       std::move(progress));
}

py::array_t<double> filtered(const py::array& positions, const py::array& colors, MapInterpolation interpolation,
                             const py::array& means_array, const py::array& sigmas_array) {
    const ColorMap map = map_from_knots(positions, colors, interpolation);
    auto means = Doubles::ensure(means_array);
    auto sigmas = Doubles::ensure(sigmas_array);
    if (!means || !sigmas || means.size() != sigmas.size())
        throw ArgumentError("means and sigmas must be arrays of the same size");
    const py::ssize_t n = means.size();
    py::array_t<double> out({n, static_cast<py::ssize_t>(map.channels)});
    double* o = out.mutable_data();
    const double* mp = means.data();
    const double* sp = sigmas.data();
    {
        py::gil_scoped_release release;
        for (py::ssize_t i = 0; i < n; ++i)
            filtered_color(map, mp[i], sp[i], o + i * map.channels);
    }
    return out;
}

py::dict lut_accuracy(const py::array& positions, const py::array& colors, MapInterpolation interpolation,
                      const py::array& table, double sigma_max, double mean_min, double mean_max,
                      SigmaSpacing sigma_spacing, int probes) {
    const ColorMap map = map_from_knots(positions, colors, interpolation);
    Image image = array_to_image(table, "table");
    const LookupSpec spec = make_spec(image.width, image.height, sigma_max, mean_min, mean_max, sigma_spacing);
    LookupAccuracy a;
    {
        py::gil_scoped_release release;
        a = measure_lookup_accuracy(map, spec, image, probes);
    }
    return accuracy_dict(a);
}

void bind_lookups(py::module_& m) {
    const LookupSpec spec;  // the core's defaults
    // ---- The contract -------------------------------------------------------
    m.def("lut", &lut, py::arg("colors"), py::arg("width"), py::arg("height"), py::arg("sigma_max"),
          py::arg("mean_min"), py::arg("mean_max"), py::arg("sigma_spacing") = spec.sigma_spacing,
          py::arg("progress") = py::none(),
    "Pre-filtered colour-map lookup L(mean, sigma) = (C * N(0, sigma^2))(mean), exact (closed form through erf).\n"
    "colors: (K, channels) samples of C at K evenly spaced positions on [0, 1], joined linearly, clamped outside.\n"
    "Returns float32 (height, width, channels): column x holds mean = mean_min + (mean_max - mean_min) x/(width-1);\n"
    "row y holds sigma = sigma_max y/(height-1) (LINEAR, the default) or sigma_max (y/(height-1))^2 (QUADRATIC).");

    // ---- Colour maps given as knots -----------------------------------------
    m.def("lut_knots", &lut_knots, py::arg("positions"), py::arg("colors"), py::arg("interpolation"),
          py::arg("width"), py::arg("height"), py::arg("sigma_max"), py::arg("mean_min"), py::arg("mean_max"),
          py::arg("sigma_spacing") = spec.sigma_spacing, py::arg("progress") = py::none(),
    "lut for a map given as knots (positions ascending in [0, 1], colors (K, channels)) joined LINEAR or held "
    "CONSTANT (MapInterpolation, or its name).");

    m.def("filtered", &filtered, py::arg("positions"), py::arg("colors"), py::arg("interpolation"), py::arg("means"),
          py::arg("sigmas"), "Exact L(mean, sigma) at each (mean, sigma) pair: (N, channels) float64.");

    m.def("lut_accuracy", &lut_accuracy, py::arg("positions"), py::arg("colors"), py::arg("interpolation"),
          py::arg("table"), py::arg("sigma_max"), py::arg("mean_min"), py::arg("mean_max"),
          py::arg("sigma_spacing") = spec.sigma_spacing, py::arg("probes") = 300,
    "Bilinear lookup in `table` (as a texture reads it, clamped at the edges) against the exact value: "
    "dict(max_abs_error, rms_error, worst_mean, worst_sigma).");
}

py::array_t<float> evaluate(const py::array& stops, const py::array& positions_array, RampInterpolation interpolation,
                            RampColorMode color_mode, RampHueInterpolation hue_interpolation) {
    const ColorRamp ramp = make_ramp(stops, interpolation, color_mode, hue_interpolation);
    auto positions = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(positions_array);
    if (!positions)
        throw ArgumentError("positions must be a numeric array");
    py::array_t<float> out({positions.size(), py::ssize_t{4}});
    float* o = out.mutable_data();
    for (py::ssize_t i = 0; i < positions.size(); ++i) {
        const auto c = evaluate_ramp(ramp, positions.data()[i]);
        std::copy(c.begin(), c.end(), o + 4 * i);
    }
    return out;
}

py::dict ramp_to_knots(const py::array& stops, RampInterpolation interpolation, RampColorMode color_mode,
                       RampHueInterpolation hue_interpolation, RampSampling sampling, int channels,
                       int dense_samples, int table_size) {
    const ColorRamp ramp = make_ramp(stops, interpolation, color_mode, hue_interpolation);
    const ColorMap map = ramp_to_color_map(ramp, sampling, channels, dense_samples, table_size);
    py::array_t<double> positions(static_cast<py::ssize_t>(map.positions.size()));
    std::copy(map.positions.begin(), map.positions.end(), positions.mutable_data());
    py::array_t<double> colors({static_cast<py::ssize_t>(map.knot_count()), static_cast<py::ssize_t>(map.channels)});
    std::copy(map.colors.begin(), map.colors.end(), colors.mutable_data());
    py::dict result;
    result["positions"] = positions;
    result["colors"] = colors;
    result["interpolation"] = map.interpolation;
    result["max_sampling_error"] = ramp_sampling_error(ramp, map);
    return result;
}

void bind_ramps(py::module_& m) {
    const ColorRamp ramp;  // the core's defaults, which are Blender's
    m.def("evaluate_ramp", &evaluate, py::arg("stops"), py::arg("positions"),
          py::arg("interpolation") = ramp.interpolation, py::arg("color_mode") = ramp.color_mode,
          py::arg("hue_interpolation") = ramp.hue_interpolation,
    "Blender's ColorRamp evaluation (BKE_colorband_evaluate) at each position: (N, 4) float32 RGBA.\n"
    "stops: (count, 5) rows of position, red, green, blue, alpha (scene-linear). Modes are Blender's enum names.");

    m.def("ramp_to_knots", &ramp_to_knots, py::arg("stops"), py::arg("interpolation") = ramp.interpolation,
          py::arg("color_mode") = ramp.color_mode, py::arg("hue_interpolation") = ramp.hue_interpolation,
          // What lookups are built from by default: a filtered lookup converges to the plain ramp's render.
          py::arg("sampling") = RampSampling::cycles_table, py::arg("channels") = 4, py::arg("dense_samples") = 1024,
          py::arg("table_size") = cycles_3x_ramp_table_size,
    "A ColorRamp as colour-map knots: sampling CYCLES (the table the renderer renders with: table_size "
    "entries at i/(table_size - 1); 256 for Cycles in Blender 3.x, 257 for EEVEE and for Cycles 4.5+) or EXACT "
    "(stops themselves where the ramp is piecewise linear/constant, else dense_samples samples). Returns "
    "dict(positions, colors, interpolation (MapInterpolation), max_sampling_error against BKE_colorband_evaluate).");
}

void bind_microsurface(py::module_& m) {
    // ---- Microsurface statistics (paper Sec. 5) ------------------------------
    m.def("smith_lambda", &smith_lambda, py::arg("theta"), py::arg("sigma_slope"),
          "Smith Λ for Gaussian slopes (paper Eq. 3); +inf at grazing.");
    m.def("smith_lambda_of_a", &smith_lambda_of_a, py::arg("a"), "Smith Λ of a = cot θ / σ_s.");
    m.def("average_visibility", &average_visibility, py::arg("lambda_view"), py::arg("lambda_light"),
          "Paper Eq. 13: (1 + Λo) / (1 + Λo + Λi).");
    m.def("effective_height", [](double lambda_sum, HeightMethod method) {
        const HeightStatistics h =
            method == HeightMethod::exact ? effective_height_exact(lambda_sum) : effective_height_fit(lambda_sum);
        return py::make_tuple(h.mean, h.stddev);
    }, py::arg("lambda_sum"), py::arg("method") = HeightMethod::exact,
    "(μ_d/σ_h, σ_d/σ_h) of the effective height distribution for Λ(ω_o)+Λ(ω_i): EXACT (numerical, log "
    "space) or FIT (paper Eqs. 17-18).");
    m.def("slope_filtering", [](double theta, double phi, std::array<double, 2> mean, std::array<double, 3> cov,
                                SlopeMethod method, int grid) {
        const SlopeStatistics s = method == SlopeMethod::gaussian
                                      ? slope_filtering_gaussian(theta, phi, mean, cov)
                                      : slope_filtering_numerical(theta, phi, mean, cov, grid);
        return py::make_tuple(s.mean, s.covariance);
    }, py::arg("theta_view"), py::arg("phi_view"), py::arg("slope_mean"), py::arg("slope_covariance"),
    py::arg("method") = SlopeMethod::gaussian, py::arg("grid") = 801,
    "Mean slope and covariance (xx, xy, yy) of the view-dependent slope filtering distribution D_s.");
    m.def("slope_shift", [](double c) {
        const SlopeShift s = slope_shift_of_c(c);
        return py::make_tuple(s.mean, s.stddev);
    }, py::arg("c"), "(E[z], sd[z]) along the view azimuth for c = cot θ_o / σ_s (zero-mean slopes).");
}

}  // namespace

void bind_colormap(py::module_& m) {
    bind_enums(m);
    bind_lookups(m);
    bind_ramps(m);
    bind_microsurface(m);
}

}  // namespace penumbra::bindings
