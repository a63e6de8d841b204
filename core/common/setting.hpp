// The valid range of a user-facing setting, declared beside the settings
// struct whose member initialiser holds its default. The core validates
// against it, the bindings take their defaults from a default-constructed
// struct, and settings_spec() (plugin/bind_settings.cpp) lists both, so the
// add-on's properties can be checked against them
// (tests/blender/test_settings.py).
#pragma once

#include <limits>
#include <string>

#include "common/error.hpp"

namespace penumbra {

template <class T>
struct Range {
    T min;
    T max;
    bool contains(T value) const { return value >= min && value <= max; }  // false for NaN
};

inline constexpr double unbounded = std::numeric_limits<double>::infinity();
inline constexpr int unbounded_int = std::numeric_limits<int>::max();

// Worker threads of any operation: 0 means as many as the process allows.
inline constexpr Range<int> threads_range{0, 1024};

// Throws ArgumentError "<what> must be in [min, max], got <value>".
template <class T>
void check_range(const char* what, T value, const Range<T>& range) {
    if (!range.contains(value))
        throw ArgumentError(std::string(what) + " must be in [" + std::to_string(range.min) + ", " +
                            (range.max == std::numeric_limits<T>::max() ||
                                     range.max == std::numeric_limits<T>::infinity()
                                 ? std::string("inf")
                                 : std::to_string(range.max)) +
                            "], got " + std::to_string(value));
}

}  // namespace penumbra
