// _penumbra.sh, basis, zonal harmonics, rotation and projection: numpy
// float64 in and out (images float32), inputs copied before the GIL is
// released.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cmath>
#include <string>
#include <vector>

#include "arrays.hpp"
#include "bindings.hpp"
#include "progress.hpp"
#include "sh/basis.hpp"
#include "sh/point_sets.hpp"
#include "sh/projection.hpp"
#include "sh/rotation.hpp"
#include "sh/zonal.hpp"

namespace py = pybind11;

namespace penumbra::bindings {

namespace {

// (N, 3) or a single (3,) direction -> vectors. Zero or non-finite rows are
// left to the core, which names them in its ArgumentError.
std::vector<Eigen::Vector3d> to_directions(const Doubles& a, const char* what) {
    const bool single = a.ndim() == 1 && a.shape(0) == 3;
    if (!single && !(a.ndim() == 2 && a.shape(1) == 3))
        throw py::value_error(std::string(what) + " must have shape (N, 3) or (3,), got " + shape_of(a));
    const py::ssize_t n = single ? 1 : a.shape(0);
    std::vector<Eigen::Vector3d> out(n);
    const double* p = a.data();
    for (py::ssize_t i = 0; i < n; ++i) out[i] = Eigen::Vector3d(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
    return out;
}

py::array_t<double> eval(int order, const Doubles& dirs) {
    sh::check_order(order);
    const std::vector<Eigen::Vector3d> d = to_directions(dirs, "dirs");
    Eigen::MatrixXd y(d.size(), sh::coefficient_count(order));
    {
        py::gil_scoped_release release;
        Eigen::VectorXd row(y.cols());
        for (std::size_t i = 0; i < d.size(); ++i) {
            sh::eval(order, d[i], row.data());
            y.row(Eigen::Index(i)) = row.transpose();
        }
    }
    return dirs.ndim() == 1 ? matrix_to_array(y.transpose(), true) : matrix_to_array(y);
}

py::object project_environment(int order, const py::array& image, const py::object& progress, bool with_stats) {
    if (image.ndim() != 3 || (image.shape(2) != 3 && image.shape(2) != 4))
        throw py::value_error("image must have shape (H, W, 3) or (H, W, 4), got " + shape_of(image));
    const auto pixels = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(image);
    if (!pixels) throw py::value_error("image must be a real-valued array");
    const int h = int(image.shape(0)), w = int(image.shape(1)), c = int(image.shape(2));
    const std::vector<float> copy(pixels.data(), pixels.data() + pixels.size());
    PyProgress py_progress(progress);
    sh::EnvironmentProjection result;
    try {
        py::gil_scoped_release release;
        result = sh::project_equirectangular(order, copy.data(), h, w, c, py_progress.progress());
    } catch (const Cancelled&) {
        py_progress.rethrow_if_failed();
        throw;
    }
    py::array_t<double> coefficients = matrix_to_array(result.coefficients);
    if (!with_stats) return py::object(coefficients);
    py::dict stats;
    stats["non_finite_pixels"] = result.non_finite_pixels;
    stats["negative_pixels"] = result.negative_pixels;
    return py::object(py::make_tuple(coefficients, stats));
}

py::array_t<double> zh_to_sh(int order, const Doubles& axes, const Doubles& bands) {
    sh::check_order(order);
    const std::vector<Eigen::Vector3d> a = to_directions(axes, "axes");
    const bool single = bands.ndim() == 1;
    if (!((single && bands.shape(0) == order && a.size() == 1) ||
          (bands.ndim() == 2 && bands.shape(0) == py::ssize_t(a.size()) && bands.shape(1) == order)))
        throw py::value_error("bands must have shape (C, order) = (" + std::to_string(a.size()) + ", " +
                              std::to_string(order) + ") to match axes, got " + shape_of(bands));
    const std::vector<double> g(bands.data(), bands.data() + bands.size());
    Eigen::VectorXd sh_coefficients = Eigen::VectorXd::Zero(sh::coefficient_count(order));
    {
        py::gil_scoped_release release;
        for (std::size_t i = 0; i < a.size(); ++i)
            sh::zh_to_sh_accumulate(order, a[i], g.data() + i * order, sh_coefficients.data());
    }
    return matrix_to_array(sh_coefficients, true);
}

py::array_t<double> rotate_zh(const Doubles& axes, const Doubles& rotation) {
    const std::vector<Eigen::Vector3d> a = to_directions(axes, "axes");
    const Eigen::Matrix3d r = matrix3(rotation, "rotation");
    static_cast<void>(sh::ShRotation(1, r));  // validates r as a proper rotation
    Eigen::MatrixXd out(a.size(), 3);
    for (std::size_t i = 0; i < a.size(); ++i) {
        sh::ZhLobe lobe;
        lobe.axis = a[i];
        out.row(Eigen::Index(i)) = sh::rotate_lobe(lobe, r).axis.transpose();
    }
    return axes.ndim() == 1 ? matrix_to_array(out.transpose(), true) : matrix_to_array(out);
}

py::array_t<double> rotate(const Doubles& coeffs, const Doubles& rotation) {
    const Eigen::MatrixXd c = array_to_matrix(coeffs, "coeffs");
    const int order = order_of_coefficient_count(c.rows(), sh::max_order, "coeffs");
    const Eigen::Matrix3d r = matrix3(rotation, "rotation");
    Eigen::MatrixXd out;
    {
        py::gil_scoped_release release;
        out = sh::ShRotation(order, r).apply(c);
    }
    return matrix_to_array(out, coeffs.ndim() == 1);
}

py::array_t<double> project_points(int order, const Doubles& dirs, const Doubles& values, const py::object& weights) {
    sh::check_order(order);
    const std::vector<Eigen::Vector3d> d = to_directions(dirs, "dirs");
    const Eigen::MatrixXd v = array_to_matrix(values, "values");
    if (v.rows() != Eigen::Index(d.size()))
        throw py::value_error("values must have one row per direction (" + std::to_string(d.size()) + "), got " +
                              shape_of(values));
    std::vector<double> w;
    if (!weights.is_none()) {
        const auto wa = Doubles::ensure(weights);
        if (!wa || wa.ndim() != 1 || wa.shape(0) != py::ssize_t(d.size()))
            throw py::value_error("weights must have shape (" + std::to_string(d.size()) + ",)");
        w.assign(wa.data(), wa.data() + wa.size());
    }
    Eigen::MatrixXd out;
    {
        py::gil_scoped_release release;
        out = sh::project_samples(order, d, v, w);
    }
    return matrix_to_array(out, values.ndim() == 1);
}

py::array_t<double> project_lights(int order, const Doubles& dirs, const Doubles& rgb) {
    sh::check_order(order);
    const std::vector<Eigen::Vector3d> d = to_directions(dirs, "dirs");
    if (rgb.ndim() != 2 || rgb.shape(0) != py::ssize_t(d.size()) || rgb.shape(1) != 3)
        throw py::value_error("rgb must have shape (" + std::to_string(d.size()) + ", 3), got " + shape_of(rgb));
    const Eigen::MatrixXd e = array_to_matrix(rgb, "rgb");
    Eigen::MatrixXd out;
    {
        py::gil_scoped_release release;
        out = sh::project_lights(order, d, e);
    }
    return matrix_to_array(out);
}

py::array_t<double> fibonacci_directions(int n) {
    sh::PointSet set;
    {
        py::gil_scoped_release release;
        set = sh::fibonacci_sphere(n);
    }
    Eigen::MatrixXd out(n, 3);
    for (int i = 0; i < n; ++i) out.row(i) = set.directions[i].transpose();
    return matrix_to_array(out);
}

}  // namespace

void bind_sh(py::module_& m) {
    m.attr("MAX_ORDER") = sh::max_order;

    m.def("eval", &eval, py::arg("order"), py::arg("dirs"),
    "Real SH basis (convention in core/sh/basis.hpp) at directions (N, 3) -> (N, order²); "
    "a single (3,) direction gives (order²,). Directions are normalized; zero or NaN -> ValueError.");

    m.def("project_environment", &project_environment, py::arg("order"), py::arg("image"),
          py::arg("progress") = py::none(), py::arg("with_stats") = false,
    "Projects an equirectangular float image (H, W, 3|4; row 0 = top of the file, alpha ignored) oriented as "
    "Blender's World shows it (centre = +x, top = +z; see core/sh/projection.hpp) to (order², 3) RGB "
    "coefficients. NaN/Inf channels count as 0. with_stats=True returns (coefficients, "
    "{'non_finite_pixels', 'negative_pixels'}). progress(fraction) -> False cancels.");

    m.def("zh_to_sh", &zh_to_sh, py::arg("order"), py::arg("axes"), py::arg("bands"),
    "Sum of ZH lobes (axes (C, 3), band coefficients (C, order)) as SH coefficients (order²,), paper Eq. 1.");

    m.def("rotate_zh", &rotate_zh, py::arg("axes"), py::arg("rotation"),
    "Turns ZH lobe axes (C, 3) by a 3x3 rotation: returns normalized R·axis. Band coefficients are unchanged.");

    m.def("rotate", &rotate, py::arg("coeffs"), py::arg("rotation"),
    "Coefficients (order²,) or (order², k) of the function rotated by R, g(ω) = f(Rᵀω).");

    m.def("project_points", &project_points, py::arg("order"), py::arg("dirs"), py::arg("values"),
          py::arg("weights") = py::none(),
    "Σ weights·values·y(dirs): (N,) or (N, k) values -> (order²,) or (order², k). "
    "weights=None means 4π/N each.");

    m.def("project_lights", &project_lights, py::arg("order"), py::arg("dirs"), py::arg("rgb"),
    "Distant delta lights (direction towards the light, RGB irradiance) -> (order², 3): E·y(d) each.");

    m.def("fibonacci_directions", &fibonacci_directions, py::arg("n"),
          "n spherical-Fibonacci unit directions (n, 3); each has solid angle 4π/n.");
}

}  // namespace penumbra::bindings
