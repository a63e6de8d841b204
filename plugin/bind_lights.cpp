// Bindings for core/lights (filled in by the lights work).
#include <pybind11/pybind11.h>

#include "bindings.hpp"

namespace penumbra::bindings {

void bind_lights(pybind11::module_&) {}

}  // namespace penumbra::bindings
