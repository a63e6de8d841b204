// Little-endian binary payloads for Penumbra's own file formats (the
// visibility baker's .pzh and .pvis, visibility/model_file.hpp): a Writer
// that appends plain values, strings and arrays to a byte string, and a
// Reader that takes them back out, checking every count against the bytes
// left before it reads, so a truncated or corrupted file is an IoError
// naming the file, never a read past the end. Layouts (header, checksum,
// field order) belong to each format.
// Tests: tests/cpp/common/binary_io_test.cpp.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

namespace penumbra {

static_assert(std::endian::native == std::endian::little, "Penumbra's files are little-endian");

// Longest string a file may hold (bone names, summary keys).
constexpr std::uint32_t max_name_bytes = 4096;

class BinaryWriter {
public:
    // T is trivially copyable (integers, float, double), written as in memory.
    template <typename T> void put(T value) { append(&value, sizeof value); }
    // u32 length + bytes; ArgumentError above max_name_bytes.
    void put_string(const std::string& s);
    // u32 count + each string.
    void put_strings(const std::vector<std::string>& names);
    // The elements only: the format writes (or implies) the count.
    template <typename T> void put_array(const std::vector<T>& a) { append(a.data(), a.size() * sizeof(T)); }
    const std::string& bytes() const { return bytes_; }

private:
    void append(const void* p, std::size_t n) { bytes_.append(static_cast<const char*>(p), n); }
    std::string bytes_;
};

class BinaryReader {
public:
    // `path` and `kind` ("Penumbra visibility file") name what failed:
    // "'<path>' is not a valid <kind>: <why>".
    BinaryReader(std::string path, std::string kind, const char* data, std::size_t size)
        : path_(std::move(path)), kind_(std::move(kind)), data_(data), size_(size) {}

    template <typename T> T get() {
        need(sizeof(T), "a field");
        T value;
        std::memcpy(&value, data_ + at_, sizeof(T));
        at_ += sizeof(T);
        return value;
    }
    std::string get_string();
    // At most `limit` strings, else fail().
    std::vector<std::string> get_strings(std::uint32_t limit);
    // `count` elements; fail() naming `what` when fewer bytes are left.
    template <typename T> std::vector<T> get_array(std::uint64_t count, const char* what) {
        if (count > (size_ - at_) / sizeof(T)) fail(std::string("it ends inside ") + what);
        std::vector<T> out(count);
        if (count) std::memcpy(out.data(), data_ + at_, count * sizeof(T));  // never memcpy from/to null
        at_ += count * sizeof(T);
        return out;
    }
    // fail() unless every byte was read.
    void expect_end();
    // Throws IoError "'<path>' is not a valid <kind>: <why>".
    [[noreturn]] void fail(const std::string& why) const;

private:
    void need(std::size_t n, const char* what);
    std::string path_, kind_;
    const char* data_;
    std::size_t size_;
    std::size_t at_ = 0;
};

}  // namespace penumbra
