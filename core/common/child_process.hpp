// A program run as a child process whose standard output we read, for the
// work that must not share Blender's address space (decoding video: see
// image/video.hpp). POSIX only, like the package (docs/packaging.md).
//
// The child's stderr goes to an anonymous temporary file, not a pipe, so a
// chatty child can never block on a pipe nobody reads; its text becomes the
// error message. The destructor kills a child that is still running and
// reaps it, so an exception or a cancel never leaves a process behind.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace penumbra {

class ChildProcess {
public:
    // Starts argv[0] (searched in PATH when it has no '/'). Throws IoError
    // naming the program when it cannot be started.
    explicit ChildProcess(const std::vector<std::string>& argv);
    ~ChildProcess();
    ChildProcess(const ChildProcess&) = delete;
    ChildProcess& operator=(const ChildProcess&) = delete;

    // Reads exactly `size` bytes of the child's stdout; false at end of
    // output before `size` bytes (what was read is in `data`).
    bool read_exact(void* data, std::size_t size);
    // All of stdout that is left.
    std::string read_all();

    // Waits for the child to exit: its exit status (128 + signal when it was
    // killed by one). `stderr_text()` is complete afterwards.
    int wait();
    // What the child wrote to stderr, trimmed to its last `max_bytes`.
    std::string stderr_text(std::size_t max_bytes = 2000) const;

private:
    int pid_ = -1;
    int stdout_fd_ = -1;
    int stderr_fd_ = -1;
    int status_ = -1;
};

}  // namespace penumbra
