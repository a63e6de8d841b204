// What this build of the core was made with and links against, for bug
// reports and for checking that a Blender process loaded the right libraries.
#pragma once

#include <map>
#include <string>

namespace penumbra {

// Keys: version, compiler (filled by the caller), simd, openimageio,
// openimageio_runtime, opencolorio, embree, eigen.
std::map<std::string, std::string> build_info();

}  // namespace penumbra
