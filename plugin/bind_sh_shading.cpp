// _penumbra.sh, batched pose shading (core/sh/pose_shading.hpp): numpy in,
// float32 RGB out. Inputs are copied (as float32, or float64 when every float input is
// float64) before the GIL is released; shaders are cached per order.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "arrays.hpp"
#include "bindings.hpp"
#include "enums.hpp"
#include "sh/basis.hpp"
#include "sh/pose_shading.hpp"

namespace py = pybind11;

namespace penumbra::bindings {
namespace {

// The checked shape of an input, or ValueError naming it and what was expected.
void expect_shape(const py::array& a, const char* what, std::initializer_list<py::ssize_t> shape,
                  const std::string& expected) {
    bool ok = a.ndim() == py::ssize_t(shape.size());
    py::ssize_t axis = 0;
    for (const py::ssize_t extent : shape) {
        if (!ok) break;
        ok = a.shape(axis++) == extent;
    }
    if (!ok) throw py::value_error(std::string(what) + " must have shape " + expected + ", got " + shape_of(a));
}

template <typename Real>
std::vector<Real> copy_of(const py::array& a, const char* what) {
    const auto typed = py::array_t<Real, py::array::c_style | py::array::forcecast>::ensure(a);
    if (!typed) throw py::value_error(std::string(what) + " must be a real-valued array");
    return std::vector<Real>(typed.data(), typed.data() + typed.size());
}

// One shader per order, kept for the life of the module: it caches the Phong
// operators of recent exponents.
std::shared_ptr<const sh::PoseShader> shader_for(int order) {
    static std::mutex mutex;
    static std::map<int, std::shared_ptr<const sh::PoseShader>> shaders;
    std::lock_guard<std::mutex> lock(mutex);
    auto& shader = shaders[order];
    if (!shader) shader = std::make_shared<const sh::PoseShader>(order);
    return shader;
}

struct Inputs {
    std::size_t n = 0;
    int lobes = 0;
    py::array lobe_axes, lobe_bands, normals, tangents;
    std::optional<py::array> positions;
};

template <typename Real>
sh::ShadingStats shade(const sh::PoseShader& shader, const Inputs& in, const Eigen::MatrixXd& lighting,
                       const sh::ShadingParameters& parameters, float* rgb_out, float* visibility_out) {
    const std::vector<Real> axes = copy_of<Real>(in.lobe_axes, "lobe_axes");
    const std::vector<Real> bands = copy_of<Real>(in.lobe_bands, "lobe_bands");
    const std::vector<Real> normals = copy_of<Real>(in.normals, "normals");
    const std::vector<Real> tangents = copy_of<Real>(in.tangents, "tangents");
    const std::vector<Real> positions = in.positions ? copy_of<Real>(*in.positions, "positions") : std::vector<Real>{};
    py::gil_scoped_release release;
    std::vector<Real> rgb(in.n * 3), visibility(visibility_out ? in.n : 0);
    sh::PoseBuffers<Real> buffers{in.n, in.lobes, axes.data(), bands.data(), normals.data(), tangents.data(),
                                  positions.empty() ? nullptr : positions.data(), rgb.data(),
                                  visibility_out ? visibility.data() : nullptr};
    const sh::ShadingStats stats = shader.shade(lighting, parameters, buffers);
    for (std::size_t i = 0; i < rgb.size(); ++i) rgb_out[i] = static_cast<float>(rgb[i]);
    for (std::size_t i = 0; i < visibility.size(); ++i) visibility_out[i] = static_cast<float>(visibility[i]);
    return stats;
}

// The shapes of one pose's inputs: ValueError naming the first that is wrong.
Inputs checked_inputs(int order, const py::array& lighting, const py::array& lobe_axes, const py::array& lobe_bands,
                      const py::array& normals, const py::array& tangents) {
    const py::ssize_t count = sh::coefficient_count(order);
    const std::string o = std::to_string(order);
    expect_shape(lighting, "lighting", {count, 3}, "(order², 3) = (" + std::to_string(count) + ", 3)");
    if (lobe_axes.ndim() != 3 || lobe_axes.shape(2) != 3)
        throw py::value_error("lobe_axes must have shape (N, C, 3), got " + shape_of(lobe_axes));
    const py::ssize_t n = lobe_axes.shape(0), c = lobe_axes.shape(1);
    if (c < 1) throw py::value_error("lobe_axes needs at least one lobe per vertex, got " + shape_of(lobe_axes));
    const std::string nc = std::to_string(n) + ", " + std::to_string(c);
    expect_shape(lobe_bands, "lobe_bands", {n, c, order}, "(N, C, order) = (" + nc + ", " + o + ")");
    expect_shape(normals, "normals", {n, 3}, "(N, 3) = (" + std::to_string(n) + ", 3)");
    expect_shape(tangents, "tangents", {n, 3}, "(N, 3) = (" + std::to_string(n) + ", 3)");
    return Inputs{std::size_t(n), int(c), lobe_axes, lobe_bands, normals, tangents, std::nullopt};
}

// The (order², 3) lighting, its shape checked by checked_inputs.
Eigen::MatrixXd lighting_matrix(const py::array& lighting) {
    const auto light = Doubles::ensure(lighting);
    if (!light) throw py::value_error("lighting must be a real-valued array");
    return array_to_matrix(light, "lighting");
}

py::object shade_pose(int order, const py::array& lighting, const py::array& lobe_axes, const py::array& lobe_bands,
                      const py::array& normals, const py::array& tangents, sh::ShadingModel brdf, double exponent,
                      const std::optional<py::array>& positions, const std::optional<std::array<double, 3>>& camera,
                      const std::array<double, 3>& transmission, int threads, bool with_stats) {
    sh::check_order(order);
    Inputs in = checked_inputs(order, lighting, lobe_axes, lobe_bands, normals, tangents);
    const auto n = py::ssize_t(in.n);
    sh::ShadingParameters parameters;
    parameters.model = brdf;
    parameters.phong_exponent = exponent;
    parameters.transmission = transmission;
    parameters.threads = threads;
    if (parameters.model == sh::ShadingModel::phong) {
        if (!positions || !camera)
            throw py::value_error("brdf='phong' needs positions (N, 3) and camera (3,) for the local viewer");
        expect_shape(*positions, "positions", {n, 3}, "(N, 3) = (" + std::to_string(n) + ", 3)");
        parameters.camera = Eigen::Vector3d((*camera)[0], (*camera)[1], (*camera)[2]);
        in.positions = *positions;
    }
    const Eigen::MatrixXd l = lighting_matrix(lighting);

    // float64 arithmetic either way; float64 buffers only when every
    // float input already is float64 (no rounding of the caller's data).
    const auto is_double = [](const py::array& a) { return a.dtype().is(py::dtype::of<double>()); };
    const bool doubles = is_double(lobe_axes) && is_double(lobe_bands) && is_double(normals) &&
                         is_double(tangents) && (!in.positions || is_double(*in.positions));

    const std::shared_ptr<const sh::PoseShader> shader = shader_for(order);
    py::array_t<float> rgb({n, py::ssize_t(3)});
    py::array_t<float> visibility({with_stats ? n : py::ssize_t(0)});
    float* visibility_out = with_stats ? visibility.mutable_data() : nullptr;
    const sh::ShadingStats stats =
        doubles ? shade<double>(*shader, in, l, parameters, rgb.mutable_data(), visibility_out)
                : shade<float>(*shader, in, l, parameters, rgb.mutable_data(), visibility_out);
    if (!with_stats) return py::object(rgb);
    py::dict info;
    info["visibility"] = visibility;
    info["invalid_vertices"] = stats.invalid_vertices;
    return py::object(py::make_tuple(rgb, info));
}

}  // namespace

void bind_sh_shading(py::module_& m) {
    bind_enum<sh::ShadingModel>(m, "ShadingModel", "brdf",
        {{"DIFFUSE", sh::ShadingModel::diffuse}, {"PHONG", sh::ShadingModel::phong},
         {"TRANSLUCENT", sh::ShadingModel::translucent}},
        "The BRDF a pose is shaded with: DIFFUSE ((1/pi) clamped cosine), PHONG (normalized Phong about the "
        "reflected view), TRANSLUCENT (diffuse plus thin-membrane transmission).");

    const sh::ShadingParameters defaults;  // every default below is the core's own
    m.def("shade_pose", &shade_pose,
    py::arg("order"), py::arg("lighting"), py::arg("lobe_axes"), py::arg("lobe_bands"), py::arg("normals"),
    py::arg("tangents"), py::kw_only(), py::arg("brdf") = defaults.model,
    py::arg("exponent") = defaults.phong_exponent,
    py::arg("positions") = py::none(), py::arg("camera") = py::none(),
    py::arg("transmission") = defaults.transmission, py::arg("threads") = defaults.threads,
    py::arg("with_stats") = false,
    "Shades one pose (paper Sec. 4): per vertex, lighting^T T v with v the ZH visibility (Eq. 1) of its lobes.\n"
    "order: SH order (bands); lighting: (order^2, 3) RGB world radiance coefficients (e.g. project_environment);\n"
    "lobe_axes (N, C, 3) in each vertex's local frame (t, b, n), normalized here; lobe_bands (N, C, order);\n"
    "normals, tangents (N, 3) world (tangent Gram-Schmidt'ed against the normal).\n"
    "brdf (ShadingModel, or its name): DIFFUSE ((1/pi) clamped cosine; unit radiance + full visibility -> 1, the\n"
    "AO otherwise), PHONG (normalized Phong about r = reflect(-w, n), w = camera - position normalized; needs\n"
    "exponent >= 0, positions (N, 3) and camera (3,); r is clamped to the horizon when the camera is behind the\n"
    "surface), TRANSLUCENT (diffuse + transmission[c] * unshadowed clamped cosine about -n; Sloan et al. 2005 thin\n"
    "membrane, paper Sec. 4.1). threads: 0 = all cores. Returns float32 (N, 3) RGB; with_stats=True returns\n"
    "(rgb, {'visibility': float32 (N,) cosine-weighted visibility (AO), 'invalid_vertices': int}).\n"
    "A vertex with a zero/NaN normal, a tangent along its normal, NaN bands, a zero axis with non-zero bands or\n"
    "(phong) a NaN position shades to 0 and is counted; shape, lighting and parameter errors raise ValueError.\n"
    "See docs/sh-engine.md.");
    m.def("simd_target", &sh::simd_target,
          "The SIMD target pose shading runs on for this CPU, chosen at run time (Highway's names: AVX3 = AVX-512, "
          "AVX2, SSE4; SCALAR is the one-lane reference).");
    m.def("simd_targets", &sh::simd_targets, "Every SIMD target compiled in that this CPU supports, best first.");
    m.def("force_simd_target", &sh::force_simd_target, py::arg("name"),
          "Tests and benchmarks: shade on `name` (one of simd_targets()) from now on; '' returns to the CPU's best.");
}

}  // namespace penumbra::bindings
