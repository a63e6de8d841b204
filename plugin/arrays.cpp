#include "arrays.hpp"

#include <cmath>

#include "common/error.hpp"

namespace py = pybind11;

namespace penumbra::bindings {

std::string shape_of(const py::array& a) {
    std::string s = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
    return s + (a.ndim() == 1 ? ",)" : ")");
}

std::vector<float> triples(const Floats& a, const char* what) {
    const bool ok = (a.ndim() == 2 && a.shape(1) == 3) || (a.ndim() == 1 && a.shape(0) % 3 == 0);
    if (!ok) throw py::value_error(std::string(what) + " must have shape (N, 3), got " + shape_of(a));
    return std::vector<float>(a.data(), a.data() + a.size());
}

std::vector<std::uint32_t> indices(const Indices& a, const char* what, bool triples_only) {
    if (triples_only && !((a.ndim() == 2 && a.shape(1) == 3) || (a.ndim() == 1 && a.shape(0) % 3 == 0)))
        throw py::value_error(std::string(what) + " must have shape (M, 3), got " + shape_of(a));
    if (!triples_only && a.ndim() != 1) throw py::value_error(std::string(what) + " must be 1-dimensional");
    std::vector<std::uint32_t> out(a.size());
    const std::int64_t* p = a.data();
    for (py::ssize_t i = 0; i < a.size(); ++i) {
        if (p[i] < 0 || p[i] > 0xFFFFFFFFll) throw py::value_error(std::string(what) + " holds a negative or huge index");
        out[i] = std::uint32_t(p[i]);
    }
    return out;
}

std::vector<float> rotations(const Floats& a, std::size_t expected, const char* what) {
    const bool ok = (a.ndim() == 3 && a.shape(1) == 3 && a.shape(2) == 3) || (a.ndim() == 2 && a.shape(1) == 9) ||
                    (a.ndim() == 1 && a.shape(0) == 0);
    if (!ok) throw py::value_error(std::string(what) + " must have shape (B, 3, 3), got " + shape_of(a));
    const std::size_t count = a.ndim() == 1 ? 0 : std::size_t(a.shape(0));
    if (count != expected)
        throw py::value_error(std::string(what) + ": expected " + std::to_string(expected) + " rotations, got " +
                              std::to_string(count));
    return std::vector<float>(a.data(), a.data() + a.size());
}

std::vector<Eigen::Vector3d> vectors3(const py::array& array, const char* what, bool normalize) {
    const auto a = Doubles::ensure(array);
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

namespace {

// n × n doubles, row-major, from a (n, n) array.
template <int N>
Eigen::Matrix<double, N, N> square_matrix(const py::handle& given, const char* what) {
    const auto a = Doubles::ensure(given);
    if (!a || a.ndim() != 2 || a.shape(0) != N || a.shape(1) != N)
        throw py::value_error(std::string(what) + " must be a (" + std::to_string(N) + ", " + std::to_string(N) +
                              ") matrix, got " + (a ? shape_of(a) : std::string("another type")));
    Eigen::Matrix<double, N, N> m;
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) m(i, j) = a.at(i, j);
    return m;
}

}  // namespace

Eigen::Matrix3d matrix3(const py::handle& a, const char* what) { return square_matrix<3>(a, what); }

Eigen::Matrix4d matrix4(const py::handle& a, const char* what) { return square_matrix<4>(a, what); }

Eigen::MatrixXd array_to_matrix(const Doubles& a, const char* what) {
    if (a.ndim() != 1 && a.ndim() != 2)
        throw py::value_error(std::string(what) + " must be 1- or 2-dimensional, got " + shape_of(a));
    const py::ssize_t rows = a.shape(0), cols = a.ndim() == 2 ? a.shape(1) : 1;
    Eigen::MatrixXd m(rows, cols);
    const double* p = a.data();
    for (py::ssize_t i = 0; i < rows; ++i)
        for (py::ssize_t j = 0; j < cols; ++j) m(i, j) = p[i * cols + j];
    return m;
}

int order_of_coefficient_count(py::ssize_t count, int max_order, const char* what) {
    const int order = int(std::lround(std::sqrt(double(count))));
    if (order < 1 || order > max_order || py::ssize_t(order) * order != count)
        throw py::value_error(std::string(what) + " must hold order² SH coefficients (1, 4, 9, ..., " +
                              std::to_string(max_order * max_order) + "), got " + std::to_string(count));
    return order;
}

py::array_t<double> matrix_to_array(const Eigen::MatrixXd& m, bool flat) {
    py::array_t<double> out = flat ? py::array_t<double>({m.rows() * m.cols()})
                                   : py::array_t<double>({m.rows(), m.cols()});
    double* p = out.mutable_data();
    for (Eigen::Index i = 0; i < m.rows(); ++i)
        for (Eigen::Index j = 0; j < m.cols(); ++j) p[i * m.cols() + j] = m(i, j);
    return out;
}

}  // namespace penumbra::bindings
