#include "common/hash.hpp"

namespace penumbra {

std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t hash) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) {
        hash ^= bytes[i];
        hash *= 0x100000001b3ull;  // the FNV 64-bit prime
    }
    return hash;
}

}  // namespace penumbra
