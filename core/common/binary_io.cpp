#include "common/binary_io.hpp"

#include "common/error.hpp"

namespace penumbra {

void BinaryWriter::put_string(const std::string& s) {
    if (s.size() > max_name_bytes) throw ArgumentError("name longer than 4096 bytes: " + s.substr(0, 64) + "...");
    put(std::uint32_t(s.size()));
    append(s.data(), s.size());
}

void BinaryWriter::put_strings(const std::vector<std::string>& names) {
    put(std::uint32_t(names.size()));
    for (const auto& n : names) put_string(n);
}

std::string BinaryReader::get_string() {
    const auto n = get<std::uint32_t>();
    if (n > max_name_bytes) fail("a name is longer than 4096 bytes");
    need(n, "a name");
    std::string s(data_ + at_, n);
    at_ += n;
    return s;
}

std::vector<std::string> BinaryReader::get_strings(std::uint32_t limit) {
    const auto n = get<std::uint32_t>();
    if (n > limit) fail("too many names (" + std::to_string(n) + ")");
    std::vector<std::string> out;
    for (std::uint32_t i = 0; i < n; ++i) out.push_back(get_string());
    return out;
}

void BinaryReader::expect_end() {
    if (at_ != size_) fail("it has " + std::to_string(size_ - at_) + " unexpected bytes at the end");
}

void BinaryReader::fail(const std::string& why) const {
    throw IoError("'" + path_ + "' is not a valid " + kind_ + ": " + why);
}

void BinaryReader::need(std::size_t n, const char* what) {
    if (n > size_ - at_) fail(std::string("it ends inside ") + what + " (truncated?)");
}

}  // namespace penumbra
