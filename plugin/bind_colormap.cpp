// Bindings for core/colormap: colour maps and ColorRamps, the exact
// Gaussian-filtered lookup (paper Sec. 4.2) and the microsurface statistics
// (paper Sec. 5). numpy in and out; the GIL is released while tables build.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <string>

#include "bindings.hpp"
#include "colormap/color_map.hpp"
#include "colormap/color_ramp.hpp"
#include "colormap/lookup.hpp"
#include "colormap/microsurface.hpp"
#include "common/error.hpp"
#include "numpy_image.hpp"
#include "progress.hpp"

namespace py = pybind11;

namespace penumbra::bindings {

namespace {

using namespace penumbra::colormap;
using FloatArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

SigmaSpacing parse_spacing(const std::string& s) {
    if (s == "linear") return SigmaSpacing::linear;
    if (s == "quadratic") return SigmaSpacing::quadratic;
    throw ArgumentError("sigma_spacing must be 'linear' or 'quadratic', not '" + s + "'");
}

RampInterpolation parse_interpolation(const std::string& s) {
    if (s == "LINEAR") return RampInterpolation::linear;
    if (s == "EASE") return RampInterpolation::ease;
    if (s == "CARDINAL") return RampInterpolation::cardinal;
    if (s == "B_SPLINE") return RampInterpolation::b_spline;
    if (s == "CONSTANT") return RampInterpolation::constant;
    throw ArgumentError("interpolation must be one of LINEAR, EASE, CARDINAL, B_SPLINE, CONSTANT, not '" + s + "'");
}

RampColorMode parse_color_mode(const std::string& s) {
    if (s == "RGB") return RampColorMode::rgb;
    if (s == "HSV") return RampColorMode::hsv;
    if (s == "HSL") return RampColorMode::hsl;
    throw ArgumentError("color_mode must be RGB, HSV or HSL, not '" + s + "'");
}

RampHueInterpolation parse_hue(const std::string& s) {
    if (s == "NEAR") return RampHueInterpolation::near;
    if (s == "FAR") return RampHueInterpolation::far;
    if (s == "CW") return RampHueInterpolation::cw;
    if (s == "CCW") return RampHueInterpolation::ccw;
    throw ArgumentError("hue_interpolation must be NEAR, FAR, CW or CCW, not '" + s + "'");
}

RampSampling parse_sampling(const std::string& s) {
    if (s == "cycles") return RampSampling::cycles_table;
    if (s == "exact") return RampSampling::exact;
    throw ArgumentError("sampling must be 'cycles' or 'exact', not '" + s + "'");
}

ColorRamp make_ramp(const py::array& stops_array, const std::string& interpolation, const std::string& color_mode,
                    const std::string& hue) {
    auto stops = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(stops_array);
    if (!stops || stops.ndim() != 2 || stops.shape(1) != 5)
        throw ArgumentError("stops must be an array of shape (count, 5): position, red, green, blue, alpha");
    ColorRamp ramp;
    ramp.interpolation = parse_interpolation(interpolation);
    ramp.color_mode = parse_color_mode(color_mode);
    ramp.hue_interpolation = parse_hue(hue);
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

ColorMap map_from_knots(const py::array& positions_array, const py::array& colors_array, const std::string& interp) {
    auto positions = FloatArray::ensure(positions_array);
    auto colors = FloatArray::ensure(colors_array);
    if (!positions || positions.ndim() != 1 || !colors || colors.ndim() != 2 || colors.shape(0) != positions.shape(0))
        throw ArgumentError("knots: positions (K,) and colors (K, channels) are needed");
    if (interp != "linear" && interp != "constant")
        throw ArgumentError("interpolation must be 'linear' or 'constant'");
    std::vector<double> p(positions.data(), positions.data() + positions.size());
    std::vector<double> c(colors.data(), colors.data() + colors.size());
    return color_map_from_knots(std::move(p), std::move(c), static_cast<int>(colors.shape(1)),
                                interp == "linear" ? MapInterpolation::linear : MapInterpolation::constant);
}

py::array_t<float> lut(const ColorMap& map, const LookupSpec& spec, py::object progress) {
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

LookupSpec make_spec(int width, int height, double sigma_max, double mean_min, double mean_max, const std::string& spacing) {
    LookupSpec spec{width, height, sigma_max, mean_min, mean_max, parse_spacing(spacing)};
    spec.validate();
    return spec;
}

py::tuple knots_tuple(const ColorMap& map) {
    py::array_t<double> positions(static_cast<py::ssize_t>(map.positions.size()));
    std::copy(map.positions.begin(), map.positions.end(), positions.mutable_data());
    py::array_t<double> colors({static_cast<py::ssize_t>(map.knot_count()), static_cast<py::ssize_t>(map.channels)});
    std::copy(map.colors.begin(), map.colors.end(), colors.mutable_data());
    return py::make_tuple(positions, colors,
                          map.interpolation == MapInterpolation::linear ? "linear" : "constant");
}

py::dict accuracy_dict(const LookupAccuracy& a) {
    py::dict d;
    d["max_abs_error"] = a.max_abs_error;
    d["rms_error"] = a.rms_error;
    d["worst_mean"] = a.worst_mean;
    d["worst_sigma"] = a.worst_sigma;
    return d;
}

}  // namespace

void bind_colormap(py::module_& m) {
    // ---- The contract -------------------------------------------------------
    m.def("colormap_lut", [](const py::array& colors, int width, int height, double sigma_max, double mean_min,
                             double mean_max, const std::string& sigma_spacing, py::object progress) {
        const ColorMap map = map_from_samples(colors);
        return lut(map, make_spec(width, height, sigma_max, mean_min, mean_max, sigma_spacing), std::move(progress));
    }, py::arg("colors"), py::arg("width"), py::arg("height"), py::arg("sigma_max"), py::arg("mean_min"),
    py::arg("mean_max"), py::arg("sigma_spacing") = "linear", py::arg("progress") = py::none(),
    "Pre-filtered colour-map lookup L(mean, sigma) = (C * N(0, sigma^2))(mean), exact (closed form through erf).\n"
    "colors: (K, channels) samples of C at K evenly spaced positions on [0, 1], joined linearly, clamped outside.\n"
    "Returns float32 (height, width, channels): column x holds mean = mean_min + (mean_max - mean_min) x/(width-1);\n"
    "row y holds sigma = sigma_max y/(height-1) ('linear', the default) or sigma_max (y/(height-1))^2 ('quadratic').");

    // ---- Colour maps given as knots, ColorRamps -----------------------------
    m.def("colormap_lut_knots", [](const py::array& positions, const py::array& colors, const std::string& interpolation,
                                   int width, int height, double sigma_max, double mean_min, double mean_max,
                                   const std::string& sigma_spacing, py::object progress) {
        const ColorMap map = map_from_knots(positions, colors, interpolation);
        return lut(map, make_spec(width, height, sigma_max, mean_min, mean_max, sigma_spacing), std::move(progress));
    }, py::arg("positions"), py::arg("colors"), py::arg("interpolation"), py::arg("width"), py::arg("height"),
    py::arg("sigma_max"), py::arg("mean_min"), py::arg("mean_max"), py::arg("sigma_spacing") = "linear",
    py::arg("progress") = py::none(),
    "colormap_lut for a map given as knots (positions ascending in [0, 1], colors (K, channels)) joined 'linear' "
    "or held 'constant'.");

    m.def("colormap_filtered", [](const py::array& positions, const py::array& colors, const std::string& interpolation,
                                  const py::array& means_array, const py::array& sigmas_array) {
        const ColorMap map = map_from_knots(positions, colors, interpolation);
        auto means = FloatArray::ensure(means_array);
        auto sigmas = FloatArray::ensure(sigmas_array);
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
    }, py::arg("positions"), py::arg("colors"), py::arg("interpolation"), py::arg("means"), py::arg("sigmas"),
    "Exact L(mean, sigma) at each (mean, sigma) pair: (N, channels) float64.");

    m.def("colormap_lut_accuracy", [](const py::array& positions, const py::array& colors,
                                      const std::string& interpolation, const py::array& table, double sigma_max,
                                      double mean_min, double mean_max, const std::string& sigma_spacing, int probes) {
        const ColorMap map = map_from_knots(positions, colors, interpolation);
        Image image = array_to_image(table, "table");
        const LookupSpec spec = make_spec(image.width, image.height, sigma_max, mean_min, mean_max, sigma_spacing);
        LookupAccuracy a;
        {
            py::gil_scoped_release release;
            a = measure_lookup_accuracy(map, spec, image, probes);
        }
        return accuracy_dict(a);
    }, py::arg("positions"), py::arg("colors"), py::arg("interpolation"), py::arg("table"), py::arg("sigma_max"),
    py::arg("mean_min"), py::arg("mean_max"), py::arg("sigma_spacing") = "linear", py::arg("probes") = 300,
    "Bilinear lookup in `table` (as a texture reads it, clamped at the edges) against the exact value: "
    "dict(max_abs_error, rms_error, worst_mean, worst_sigma).");

    m.def("evaluate_color_ramp", [](const py::array& stops, const py::array& positions_array,
                                    const std::string& interpolation, const std::string& color_mode,
                                    const std::string& hue_interpolation) {
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
    }, py::arg("stops"), py::arg("positions"), py::arg("interpolation") = "LINEAR", py::arg("color_mode") = "RGB",
    py::arg("hue_interpolation") = "NEAR",
    "Blender's ColorRamp evaluation (BKE_colorband_evaluate) at each position: (N, 4) float32 RGBA.\n"
    "stops: (count, 5) rows of position, red, green, blue, alpha (scene-linear). Mode names are Blender's enums.");

    m.def("color_ramp_to_knots", [](const py::array& stops, const std::string& interpolation,
                                    const std::string& color_mode, const std::string& hue_interpolation,
                                    const std::string& sampling, int channels, int dense_samples) {
        const ColorRamp ramp = make_ramp(stops, interpolation, color_mode, hue_interpolation);
        const ColorMap map = ramp_to_color_map(ramp, parse_sampling(sampling), channels, dense_samples);
        py::dict result;
        const py::tuple knots = knots_tuple(map);
        result["positions"] = knots[0];
        result["colors"] = knots[1];
        result["interpolation"] = knots[2];
        result["max_sampling_error"] = ramp_sampling_error(ramp, map);
        return result;
    }, py::arg("stops"), py::arg("interpolation") = "LINEAR", py::arg("color_mode") = "RGB",
    py::arg("hue_interpolation") = "NEAR", py::arg("sampling") = "cycles", py::arg("channels") = 4,
    py::arg("dense_samples") = 1024,
    "A ColorRamp as colour-map knots: sampling 'cycles' (the 256-entry table Cycles renders with) or 'exact' "
    "(stops themselves where the ramp is piecewise linear/constant, else dense_samples samples). Returns "
    "dict(positions, colors, interpolation, max_sampling_error against BKE_colorband_evaluate).");

    // ---- Microsurface statistics (paper Sec. 5) ------------------------------
    m.def("smith_lambda", &smith_lambda, py::arg("theta"), py::arg("sigma_slope"),
          "Smith Λ for Gaussian slopes (paper Eq. 3); +inf at grazing.");
    m.def("smith_lambda_of_a", &smith_lambda_of_a, py::arg("a"), "Smith Λ of a = cot θ / σ_s.");
    m.def("average_visibility", &average_visibility, py::arg("lambda_view"), py::arg("lambda_light"),
          "Paper Eq. 13: (1 + Λo) / (1 + Λo + Λi).");
    m.def("effective_height", [](double lambda_sum, const std::string& method) {
        if (method != "exact" && method != "fit")
            throw ArgumentError("method must be 'exact' or 'fit'");
        const HeightStatistics h = method == "exact" ? effective_height_exact(lambda_sum) : effective_height_fit(lambda_sum);
        return py::make_tuple(h.mean, h.stddev);
    }, py::arg("lambda_sum"), py::arg("method") = "exact",
    "(μ_d/σ_h, σ_d/σ_h) of the effective height distribution for Λ(ω_o)+Λ(ω_i): 'exact' (numerical, log "
    "space) or 'fit' (paper Eqs. 17-18).");
    m.def("slope_filtering", [](double theta, double phi, std::array<double, 2> mean, std::array<double, 3> cov,
                                const std::string& method, int grid) {
        if (method != "gaussian" && method != "numerical")
            throw ArgumentError("method must be 'gaussian' or 'numerical'");
        const SlopeStatistics s = method == "gaussian" ? slope_filtering_gaussian(theta, phi, mean, cov)
                                                       : slope_filtering_numerical(theta, phi, mean, cov, grid);
        return py::make_tuple(s.mean, s.covariance);
    }, py::arg("theta_view"), py::arg("phi_view"), py::arg("slope_mean"), py::arg("slope_covariance"),
    py::arg("method") = "gaussian", py::arg("grid") = 801,
    "Mean slope and covariance (xx, xy, yy) of the view-dependent slope filtering distribution D_s.");
    m.def("slope_shift", [](double c) {
        const SlopeShift s = slope_shift_of_c(c);
        return py::make_tuple(s.mean, s.stddev);
    }, py::arg("c"), "(E[z], sd[z]) along the view azimuth for c = cot θ_o / σ_s (zero-mean slopes).");
}

}  // namespace penumbra::bindings
