#include "common/durable_file.hpp"

#include <atomic>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <system_error>
#include <unistd.h>

#include "common/error.hpp"
#include "common/fault_injection.hpp"

namespace penumbra {

namespace fs = std::filesystem;

namespace {

fs::path folder_of(const fs::path& file) { return file.has_parent_path() ? file.parent_path() : fs::path("."); }

// Flushes a file's data, or a folder's entries, to the disk. The file is
// opened again: whoever wrote it (OpenImageIO, a stream) has closed it, and
// fsync flushes the file, not one descriptor's writes.
void flush_to_disk(const fs::path& path, testing::FsyncFailure kind, const std::string& failure) {
    const bool folder = kind == testing::FsyncFailure::folder;
    testing::note_durable_step((folder ? "fsync folder " : "fsync file ") + path.string());
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | (folder ? O_DIRECTORY : 0));
    if (fd < 0)
        throw IoError(failure + ": cannot open '" + path.string() + "' to flush it (" + std::strerror(errno) + ")");
    int result = testing::take_fsync_failure(kind) ? (errno = EIO, -1) : ::fsync(fd);
    // Some file systems cannot flush a folder at all (EINVAL); SQLite goes on
    // there too, as nothing more can be done.
    if (result != 0 && folder && errno == EINVAL) result = 0;
    const int error = errno;
    ::close(fd);
    if (result != 0) throw IoError(failure + ": " + std::strerror(error));
}

void rename_into_place(const fs::path& from, const fs::path& to, const std::string& failure) {
    testing::note_durable_step("rename " + from.string() + " -> " + to.string());
    std::error_code ec;
    fs::rename(from, to, ec);
    if (ec) throw IoError(failure + ": " + ec.message());
}

std::string not_on_disk(const std::string& path) {
    return "could not write '" + path + "' to the disk; the file there before is unchanged. "
           "Check that the disk is not full, removed or failing, then write again";
}

std::string folder_not_on_disk(const std::string& path, const fs::path& folder) {
    return "wrote '" + path + "', but its folder '" + folder.string() +
           "' could not be flushed to the disk, so the new file may not survive a power cut. "
           "Check the disk, then write again";
}

}  // namespace

void write_file_durably(const std::string& path, const std::function<void(const std::string&)>& write) {
    static std::atomic<unsigned> counter{0};
    const fs::path target(path);
    const fs::path folder = folder_of(target);
    if (!fs::is_directory(folder))
        throw IoError("cannot write '" + path + "': folder '" + folder.string() +
                      "' does not exist; create it first");
    // Appended to ".", not "." + name: GCC 12 warns falsely (-Wrestrict) on that.
    std::string hidden = ".";
    hidden += target.stem().string() + ".penumbra-tmp-" + std::to_string(::getpid()) + "-" +
              std::to_string(counter++) + target.extension().string();
    const fs::path temporary = folder / hidden;
    try {
        write(temporary.string());
        flush_to_disk(temporary, testing::FsyncFailure::file, not_on_disk(path));
        rename_into_place(temporary, target, "cannot move the finished file to '" + path + "'");
    } catch (...) {
        std::error_code ignored;
        fs::remove(temporary, ignored);
        throw;
    }
    flush_to_disk(folder, testing::FsyncFailure::folder, folder_not_on_disk(path, folder));
}

void write_file_durably(const std::string& path, std::string_view bytes) {
    write_file_durably(path, [&](const std::string& temporary) {
        const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
        if (fd < 0)
            throw IoError("cannot create '" + temporary + "': " + std::strerror(errno) + " (is the folder writable?)");
        std::size_t written = 0;
        while (written < bytes.size()) {
            const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
            if (n < 0 && errno == EINTR) continue;
            if (n < 0) {
                const int error = errno;
                ::close(fd);
                throw IoError("cannot write '" + path + "': " + std::strerror(error) + " (disk full?)");
            }
            written += std::size_t(n);
        }
        if (::close(fd) != 0) throw IoError("cannot write '" + path + "': " + std::strerror(errno) + " (disk full?)");
    });
}

void replace_file_durably(const std::string& source, const std::string& target) {
    const fs::path from(source), to(target);
    flush_to_disk(from, testing::FsyncFailure::file,
                  "could not flush '" + source + "' to the disk before moving it to '" + target +
                      "'; both files are unchanged. Check that the disk is not full, removed or failing");
    rename_into_place(from, to, "cannot move '" + source + "' to '" + target + "'");
    flush_to_disk(folder_of(to), testing::FsyncFailure::folder, folder_not_on_disk(target, folder_of(to)));
    std::error_code ec;
    if (!fs::equivalent(folder_of(from), folder_of(to), ec))
        flush_to_disk(folder_of(from), testing::FsyncFailure::folder,
                      folder_not_on_disk(target, folder_of(from)));
}

}  // namespace penumbra
