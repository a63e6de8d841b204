// FNV-1a 64 (common/hash.hpp) against the published test vectors of the FNV
// reference (Fowler, Noll, Vo: draft-eastlake-fnv, "FNV-1a 64" column).
#include <gtest/gtest.h>

#include <string>

#include "common/hash.hpp"

namespace penumbra {
namespace {

std::uint64_t of(const std::string& s) { return fnv1a64(s.data(), s.size()); }

TEST(Hash, fnv1a64_matches_the_reference_vectors) {
    EXPECT_EQ(of(""), 0xcbf29ce484222325ull);
    EXPECT_EQ(of("a"), 0xaf63dc4c8601ec8cull);
    EXPECT_EQ(of("foobar"), 0x85944171f73967e8ull);
}

TEST(Hash, hashing_in_pieces_equals_hashing_the_whole) {
    const std::string whole = "visibility payload";
    EXPECT_EQ(fnv1a64(whole.data() + 10, whole.size() - 10, fnv1a64(whole.data(), 10)), of(whole));
}

}  // namespace
}  // namespace penumbra
