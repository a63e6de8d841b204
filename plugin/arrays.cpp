#include "arrays.hpp"

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

py::array_t<double> matrix_to_array(const Eigen::MatrixXd& m, bool flat) {
    py::array_t<double> out = flat ? py::array_t<double>({m.rows() * m.cols()})
                                   : py::array_t<double>({m.rows(), m.cols()});
    double* p = out.mutable_data();
    for (Eigen::Index i = 0; i < m.rows(); ++i)
        for (Eigen::Index j = 0; j < m.cols(); ++j) p[i * m.cols() + j] = m(i, j);
    return out;
}

}  // namespace penumbra::bindings
