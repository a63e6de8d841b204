// Bindings for core/shading (filled in by the shading work).
#include <pybind11/pybind11.h>

#include "bindings.hpp"

namespace penumbra::bindings {

void bind_shading(pybind11::module_&) {}

}  // namespace penumbra::bindings
