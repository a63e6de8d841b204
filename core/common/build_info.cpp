#include "common/build_info.hpp"

#include <OpenColorIO/OpenColorIO.h>
#include <OpenImageIO/imageio.h>
#include <Eigen/Core>
#include <embree3/rtcore.h>

namespace penumbra {

namespace {
std::string simd_level() {
#if defined(__AVX512F__)
    return "AVX-512";
#elif defined(__AVX2__)
    return "AVX2";
#elif defined(__AVX__)
    return "AVX";
#elif defined(__SSE4_2__)
    return "SSE4.2";
#elif defined(__SSE2__)
    return "SSE2";
#else
    return "none";
#endif
}

std::string embree_runtime_version() {
    RTCDevice device = rtcNewDevice("threads=1");
    if (!device)
        return std::string(RTC_VERSION_STRING) + " (device creation failed)";
    const long v = static_cast<long>(rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_VERSION));
    rtcReleaseDevice(device);
    return std::to_string(v / 10000) + "." + std::to_string(v / 100 % 100) + "." + std::to_string(v % 100);
}
}  // namespace

std::map<std::string, std::string> build_info() {
    return {
        {"version", PENUMBRA_VERSION},
        {"simd", simd_level()},
        {"openimageio", OIIO_VERSION_STRING},
        {"openimageio_runtime", std::to_string(OIIO::openimageio_version())},
        {"opencolorio", OCIO_NAMESPACE::GetVersion()},
        {"embree", embree_runtime_version()},
        {"eigen", std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) + "." +
                      std::to_string(EIGEN_MINOR_VERSION)},
    };
}

}  // namespace penumbra
