#include "image/atomic_file.hpp"

#include <atomic>
#include <filesystem>
#include <system_error>
#include <unistd.h>

#include "common/error.hpp"

namespace penumbra {

namespace fs = std::filesystem;

void write_atomically(const std::string& path, const std::function<void(const std::string&)>& write) {
    static std::atomic<unsigned> counter{0};
    const fs::path target(path);
    const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
    if (!fs::is_directory(folder))
        throw IoError("cannot write '" + path + "': folder '" + folder.string() +
                      "' does not exist; create it first");
    const fs::path temporary = folder / ("." + target.stem().string() + ".penumbra-tmp-" +
                                         std::to_string(::getpid()) + "-" +
                                         std::to_string(counter++) + target.extension().string());
    try {
        write(temporary.string());
        std::error_code ec;
        fs::rename(temporary, target, ec);
        if (ec)
            throw IoError("cannot move the finished file to '" + path + "': " + ec.message());
    } catch (...) {
        std::error_code ignored;
        fs::remove(temporary, ignored);
        throw;
    }
}

}  // namespace penumbra
