// Python progress callbacks for long C++ work that runs without the GIL.
#pragma once

#include <pybind11/pybind11.h>

#include <optional>

#include "common/progress.hpp"

namespace penumbra::bindings {

// Wraps an optional Python callable `progress(fraction) -> bool | None`
// (False stops the work; None or True goes on). The C++ work runs with the
// GIL released; each report re-acquires it. An exception raised by the
// callback stops the work and is re-raised by `rethrow_if_failed`.
class PyProgress {
public:
    explicit PyProgress(pybind11::object callback);
    const Progress& progress() const { return progress_; }
    void rethrow_if_failed();  // call with the GIL held

private:
    pybind11::object callback_;
    std::optional<pybind11::error_already_set> failure_;
    Progress progress_;
};

}  // namespace penumbra::bindings
