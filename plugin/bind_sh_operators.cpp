// _penumbra.sh, 1D-BRDF convolution operators (core/sh/brdf_operator.hpp):
// dense float64 (order², order²) numpy matrices T with t = T v.
#include <cmath>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "arrays.hpp"
#include "bindings.hpp"
#include "common/error.hpp"
#include "sh/brdf_operator.hpp"

namespace py = pybind11;

namespace penumbra::bindings {

void bind_sh_operators(py::module_& m) {
    m.def("phong_operator", [](int order, double alpha) {
        Eigen::MatrixXd t;
        {
            py::gil_scoped_release release;
            t = sh::phong_operator(order, alpha);
        }
        return matrix_to_array(t);
    }, py::arg("order"), py::arg("alpha"),
    "Normalized Phong convolution operator T = (alpha+1)/(2 pi) M^alpha (paper Eq. 2) in the local frame "
    "(reflection vector along +z), upper hemisphere only: a float64 (order^2, order^2) matrix, t = T @ v. "
    "1 <= order <= 16, alpha >= 0 (inf gives the limit y(z) y(z)^T).");

    m.def("diffuse_operator", [](int order) {
        Eigen::MatrixXd t;
        {
            py::gil_scoped_release release;
            t = sh::diffuse_operator(order);
        }
        return matrix_to_array(t);
    }, py::arg("order"),
    "Clamped-cosine operator T = (1/pi) integral over the hemisphere of cos(theta) y y^T "
    "(phong_operator(order, 1)); normal along +z.");

    m.def("kernel_operator", [](int order, const Doubles& k_of_mu) {
        if (k_of_mu.ndim() != 1)
            throw ArgumentError("kernel_operator: k_of_mu must be a 1D array of kernel samples");
        const std::vector<double> samples(k_of_mu.data(), k_of_mu.data() + k_of_mu.size());
        Eigen::MatrixXd t;
        {
            py::gil_scoped_release release;
            t = sh::kernel_operator(order, samples);
        }
        return matrix_to_array(t);
    }, py::arg("order"), py::arg("k_of_mu"),
    "Operator of a tabulated 1D kernel, T = integral over the hemisphere of k(cos theta) y y^T, with "
    "k_of_mu[i] = k(i/(n-1)) (n >= 2, finite) and k linear between samples: a float64 (order^2, order^2) matrix.");
}

}  // namespace penumbra::bindings
