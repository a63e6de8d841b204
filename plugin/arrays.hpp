// numpy arrays <-> C++ buffers, shared by the bindings: typed array aliases
// (any real dtype, copied to C order on the way in), shape checks that raise
// ValueError naming the argument and the shape it had, and vectors and Eigen
// matrices back out as numpy arrays.
#pragma once

#include <pybind11/numpy.h>

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace penumbra::bindings {

using Floats = pybind11::array_t<float, pybind11::array::c_style | pybind11::array::forcecast>;
using Doubles = pybind11::array_t<double, pybind11::array::c_style | pybind11::array::forcecast>;
using Indices = pybind11::array_t<std::int64_t, pybind11::array::c_style | pybind11::array::forcecast>;

// "(4, 3)", "(7,)": for error messages.
std::string shape_of(const pybind11::array& a);

// (N, 3) or flat 3N floats.
std::vector<float> triples(const Floats& a, const char* what);

// Non-negative 32-bit indices: (M, 3) or flat 3M when `triples_only`, else 1-dimensional.
std::vector<std::uint32_t> indices(const Indices& a, const char* what, bool triples_only);

// (B, 3, 3) or (B, 9) rotations, exactly `expected` of them: B × 9 floats.
std::vector<float> rotations(const Floats& a, std::size_t expected, const char* what);

// (N, 3) rows as vectors. With `normalize`, each becomes a unit vector and a
// zero or non-finite row is a ValueError naming it.
std::vector<Eigen::Vector3d> vectors3(const pybind11::array& array, const char* what, bool normalize);

template <typename T>
pybind11::array_t<T> to_array(const std::vector<T>& v, std::vector<pybind11::ssize_t> shape) {
    pybind11::array_t<T> out(shape);
    std::copy(v.begin(), v.end(), out.mutable_data());
    return out;
}

// A (3, 3) or (4, 4) real matrix (a rotation, an object's transform) as
// Eigen; anything else is a ValueError naming `what` and the shape it had.
Eigen::Matrix3d matrix3(const pybind11::handle& a, const char* what);
Eigen::Matrix4d matrix4(const pybind11::handle& a, const char* what);

// (rows,) or (rows, k) -> Eigen (rows, k); the inverse of matrix_to_array.
Eigen::MatrixXd array_to_matrix(const Doubles& a, const char* what);

// The SH order of `count` coefficients (count = order², 1 <= order <=
// max_order: sh::max_order for the SH engine, visibility::max_sh_order for
// the visibility tool), or a ValueError naming `what`.
int order_of_coefficient_count(pybind11::ssize_t count, int max_order, const char* what);

// f applied to every element: float64 of a's shape (a scalar gives a 0-d array).
template <typename F>
pybind11::array_t<double> map_elements(const Doubles& a, F&& f) {
    pybind11::array_t<double> out(std::vector<pybind11::ssize_t>(a.shape(), a.shape() + a.ndim()));
    const double* in = a.data();
    double* o = out.mutable_data();
    for (pybind11::ssize_t i = 0; i < a.size(); ++i) o[i] = f(in[i]);
    return out;
}

// Eigen (rows, k) -> float64 (rows, k), or (rows,) when `flat`.
pybind11::array_t<double> matrix_to_array(const Eigen::MatrixXd& m, bool flat = false);

}  // namespace penumbra::bindings
