#include "numpy_image.hpp"

#include <cstring>

#include "common/error.hpp"

namespace py = pybind11;

namespace penumbra::bindings {

py::array_t<float> image_to_array(Image&& image) {
    // Hand the pixel vector to numpy without a copy; a capsule owns it.
    auto* owner = new std::vector<float>(std::move(image.pixels));
    py::capsule free_when_done(owner, [](void* p) { delete static_cast<std::vector<float>*>(p); });
    return py::array_t<float>({image.height, image.width, image.channels}, owner->data(), free_when_done);
}

Image array_to_image(const py::array& array, const char* what) {
    auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(array);
    if (!a)
        throw ArgumentError(std::string(what) + " must be a numeric array of shape (height, width, channels)");
    if (a.ndim() != 2 && a.ndim() != 3)
        throw ArgumentError(std::string(what) + " must have shape (height, width) or (height, width, channels), got " +
                            std::to_string(a.ndim()) + " dimensions");
    const int h = static_cast<int>(a.shape(0)), w = static_cast<int>(a.shape(1));
    const int c = a.ndim() == 3 ? static_cast<int>(a.shape(2)) : 1;
    if (c < 1 || c > 4)
        throw ArgumentError(std::string(what) + " must have 1 to 4 channels, got " + std::to_string(c));
    if (h == 0 || w == 0)
        throw ArgumentError(std::string(what) + " is empty (" + std::to_string(h) + "x" + std::to_string(w) + ")");
    Image image(w, h, c);
    std::memcpy(image.pixels.data(), a.data(), image.pixels.size() * sizeof(float));
    return image;
}

}  // namespace penumbra::bindings
