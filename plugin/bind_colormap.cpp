// Bindings for core/colormap (filled in by the colormap work).
#include <pybind11/pybind11.h>

#include "bindings.hpp"

namespace penumbra::bindings {

void bind_colormap(pybind11::module_&) {}

}  // namespace penumbra::bindings
