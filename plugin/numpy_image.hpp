// penumbra::Image <-> numpy float32 arrays of shape (height, width, channels),
// row 0 at the top, as the core stores them.
#pragma once

#include <pybind11/numpy.h>

#include "image/image.hpp"

namespace penumbra::bindings {

pybind11::array_t<float> image_to_array(Image&& image);
// Accepts (H, W) or (H, W, C) with C in 1..4, any real dtype (copied to float32).
Image array_to_image(const pybind11::array& array, const char* what);

}  // namespace penumbra::bindings
