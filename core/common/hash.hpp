// FNV-1a 64, the one hash Penumbra's files use: the checksum of a visibility
// file's payload (visibility/model_file.hpp) and the mesh topology
// fingerprint (visibility/mesh_frames.hpp). Not cryptographic: it catches
// corruption and mismatched meshes, not tampering.
// Tests: tests/cpp/common/hash_test.cpp.
#pragma once

#include <cstddef>
#include <cstdint>

namespace penumbra {

constexpr std::uint64_t fnv1a64_offset_basis = 0xcbf29ce484222325ull;

// FNV-1a 64 over `size` bytes, continuing from `hash` (the offset basis
// starts a new hash), so pieces hashed in turn equal the whole.
std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t hash = fnv1a64_offset_basis);

}  // namespace penumbra
