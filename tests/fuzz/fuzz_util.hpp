// Shared pieces of the fuzz harnesses (docs/reliability.md).
//
// The contract every harness checks: whatever the input, the code under test
// returns or throws a penumbra::Error (what the bindings turn into a Python
// exception). Any other exception, a crash, an ASan or UBSan report, or a
// broken invariant (penumbra_fuzz_check) is a finding: the harness aborts and
// libFuzzer keeps the input as a crasher.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <type_traits>
#include <typeinfo>

#include "common/error.hpp"

namespace penumbra::fuzz {

[[noreturn]] inline void finding(const std::string& what) {
    std::fprintf(stderr, "FUZZ FINDING: %s\n", what.c_str());
    std::fflush(stderr);
    std::abort();
}

#define penumbra_fuzz_check(condition, what)                                     \
    do {                                                                         \
        if (!(condition)) ::penumbra::fuzz::finding(std::string(what) + " (" #condition ")"); \
    } while (0)

// The replay (replay_main.cpp) says what became of each input; libFuzzer runs stay quiet.
inline bool& verbose() {
    static bool on = false;
    return on;
}

// Runs `work`; a penumbra::Error is an accepted outcome, anything else a finding.
template <typename F> void expect_only_penumbra_errors(F&& work) {
    try {
        work();
        if (verbose()) std::fprintf(stderr, "  accepted\n");
    } catch (const penumbra::Error& e) {
        // The documented way to refuse bad input.
        if (verbose()) std::fprintf(stderr, "  refused: %s\n", e.what());
    } catch (const std::exception& e) {
        finding(std::string("an exception that is not a penumbra::Error escaped: ") + typeid(e).name() + ": " +
                e.what());
    } catch (...) {
        finding("an exception that is not a std::exception escaped");
    }
}

// Reads the fuzz input as a stream of fields; past the end every field is 0,
// so any input is a complete one.
class Bytes {
public:
    Bytes(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
    template <typename T> T take() {
        static_assert(std::is_trivially_copyable_v<T>);
        T value{};
        const std::size_t n = std::min(sizeof(T), size_ - at_);
        if (n) std::memcpy(&value, data_ + at_, n);
        at_ += n;
        return value;
    }
    std::uint8_t byte() { return take<std::uint8_t>(); }
    // An integer in [lo, hi].
    int in_range(int lo, int hi) { return lo + int(take<std::uint16_t>() % std::uint32_t(hi - lo + 1)); }
    std::string take_string(std::size_t n) {
        n = std::min(n, size_ - at_);
        std::string s(reinterpret_cast<const char*>(data_) + at_, n);
        at_ += n;
        return s;
    }
    std::string rest() { return take_string(size_ - at_); }
    std::size_t left() const { return size_ - at_; }

private:
    const std::uint8_t* data_;
    std::size_t size_;
    std::size_t at_ = 0;
};

// One scratch folder per process (in /dev/shm when there is one: the
// harnesses write a file per input), emptied for each input, removed at exit.
class Scratch {
public:
    static Scratch& get() {
        static Scratch* s = new Scratch;  // never destroyed: the atexit cleanup still needs it
        return *s;
    }
    // An empty folder for this input.
    const std::filesystem::path& fresh() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
        std::filesystem::create_directories(path_);
        return path_;
    }
    std::string file(const std::string& name) const { return (path_ / name).string(); }

private:
    Scratch() {
        const std::filesystem::path base =
            std::filesystem::is_directory("/dev/shm") ? std::filesystem::path("/dev/shm")
                                                      : std::filesystem::temp_directory_path();
        path_ = base / ("penumbra-fuzz-" + std::to_string(::getpid()));
        std::atexit([] {
            std::error_code ec;
            std::filesystem::remove_all(get().path_, ec);
        });
    }
    std::filesystem::path path_;
};

inline void write_file(const std::string& path, const void* data, std::size_t size) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(static_cast<const char*>(data), std::streamsize(size));
    if (!out) finding("the harness could not write " + path);
}

}  // namespace penumbra::fuzz
