// Binary payloads (common/binary_io.hpp): what the writer puts the reader
// gets back, little-endian; every overrun is an IoError naming the file.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "common/binary_io.hpp"
#include "common/error.hpp"

namespace penumbra {
namespace {

BinaryReader reader_of(const std::string& bytes) { return {"x.pzh", "test file", bytes.data(), bytes.size()}; }

TEST(BinaryIo, values_strings_and_arrays_round_trip) {
    BinaryWriter w;
    w.put(std::uint32_t(7));
    w.put(-2.5);
    w.put_string("spine.001");
    w.put_strings({"a", "", "bone"});
    w.put_array(std::vector<float>{1.0f, -0.0f, 3.5f});
    w.put_array(std::vector<std::uint16_t>{});
    BinaryReader r = reader_of(w.bytes());
    EXPECT_EQ(r.get<std::uint32_t>(), 7u);
    EXPECT_EQ(r.get<double>(), -2.5);
    EXPECT_EQ(r.get_string(), "spine.001");
    EXPECT_EQ(r.get_strings(3), (std::vector<std::string>{"a", "", "bone"}));
    EXPECT_EQ(r.get_array<float>(3, "floats"), (std::vector<float>{1.0f, -0.0f, 3.5f}));
    EXPECT_TRUE(r.get_array<std::uint16_t>(0, "nothing").empty());
    EXPECT_NO_THROW(r.expect_end());
}

TEST(BinaryIo, values_are_little_endian) {
    BinaryWriter w;
    w.put(std::uint32_t(0x04030201));
    EXPECT_EQ(w.bytes(), std::string("\x01\x02\x03\x04", 4));
}

TEST(BinaryIo, overruns_and_leftovers_are_io_errors_naming_the_file) {
    BinaryWriter w;
    w.put(std::uint32_t(3));
    const std::string bytes = w.bytes();
    try {
        reader_of(bytes.substr(0, 2)).get<std::uint32_t>();
        FAIL() << "read past the end";
    } catch (const IoError& e) {
        EXPECT_EQ(std::string(e.what()), "'x.pzh' is not a valid test file: it ends inside a field (truncated?)");
    }
    EXPECT_THROW(reader_of(bytes).get_array<double>(1, "a frame"), IoError);  // 4 bytes left, 8 needed
    EXPECT_THROW(reader_of(bytes).get_string(), IoError);                      // says 3 bytes, has 0
    EXPECT_THROW(reader_of(bytes).get_strings(2), IoError);                    // 3 names > limit 2
    EXPECT_THROW(reader_of(bytes).expect_end(), IoError);
}

TEST(BinaryIo, names_longer_than_the_limit_are_refused_both_ways) {
    BinaryWriter w;
    EXPECT_THROW(w.put_string(std::string(max_name_bytes + 1, 'x')), ArgumentError);
    w.put(std::uint32_t(max_name_bytes + 1));
    EXPECT_THROW(reader_of(w.bytes()).get_string(), IoError);
}

}  // namespace
}  // namespace penumbra
