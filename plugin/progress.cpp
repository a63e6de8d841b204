#include "progress.hpp"

namespace py = pybind11;

namespace penumbra::bindings {

PyProgress::PyProgress(py::object callback) : callback_(std::move(callback)) {
    if (callback_.is_none())
        return;
    if (!PyCallable_Check(callback_.ptr()))
        throw py::type_error("progress must be a callable taking a fraction in [0, 1], or None");
    progress_ = Progress([this](double fraction) {
        py::gil_scoped_acquire gil;
        try {
            py::object answer = callback_(fraction);
            return answer.is_none() || answer.cast<bool>();
        } catch (py::error_already_set& e) {
            failure_.emplace(std::move(e));
            return false;
        }
    });
}

void PyProgress::rethrow_if_failed() {
    if (failure_) {
        py::error_already_set e = std::move(*failure_);
        failure_.reset();
        throw e;
    }
}

}  // namespace penumbra::bindings
