// Bindings for core/visibility (filled in by the visibility work).
#include <pybind11/pybind11.h>

#include "bindings.hpp"

namespace penumbra::bindings {

void bind_visibility(pybind11::module_&) {}

}  // namespace penumbra::bindings
