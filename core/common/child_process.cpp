#include "common/child_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "common/error.hpp"

extern char** environ;

namespace penumbra {

namespace {

void close_fd(int& fd) {
    if (fd >= 0) ::close(fd);
    fd = -1;
}

// An unnamed temporary file (O_TMPFILE where the filesystem has it).
int anonymous_file() {
    const char* dir = std::getenv("TMPDIR");
    int fd = ::open(dir && *dir ? dir : "/tmp", O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
    if (fd >= 0) return fd;
    std::FILE* f = std::tmpfile();  // fallback: created and unlinked at once
    if (!f) throw IoError(std::string("cannot create a temporary file: ") + std::strerror(errno));
    fd = ::dup(fileno(f));
    std::fclose(f);
    ::fcntl(fd, F_SETFD, FD_CLOEXEC);
    return fd;
}

}  // namespace

ChildProcess::ChildProcess(const std::vector<std::string>& argv) {
    if (argv.empty()) throw ArgumentError("a child process needs a program to run");
    int pipe_fds[2];
    if (::pipe2(pipe_fds, O_CLOEXEC) != 0)
        throw IoError(std::string("cannot create a pipe: ") + std::strerror(errno));
    stdout_fd_ = pipe_fds[0];
    // A 1 MiB pipe (Linux's default limit for unprivileged processes; the
    // default is 64 KiB): a child writing whole video frames wakes us 16
    // times less often. Where it is refused the pipe keeps its size.
#ifdef F_SETPIPE_SZ
    ::fcntl(stdout_fd_, F_SETPIPE_SZ, 1 << 20);
#endif
    stderr_fd_ = anonymous_file();

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], 1);
    posix_spawn_file_actions_adddup2(&actions, stderr_fd_, 2);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    pid_t pid = -1;
    const int rc = ::posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(pipe_fds[1]);
    if (rc != 0) {
        close_fd(stdout_fd_);
        close_fd(stderr_fd_);
        throw IoError("cannot run '" + argv[0] + "': " + std::strerror(rc));
    }
    pid_ = pid;
}

ChildProcess::~ChildProcess() {
    close_fd(stdout_fd_);  // a child still writing gets EPIPE and stops
    if (pid_ > 0 && status_ < 0) {
        ::kill(pid_, SIGKILL);
        int status = 0;
        while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {}
    }
    close_fd(stderr_fd_);
}

bool ChildProcess::read_exact(void* data, std::size_t size) {
    auto* out = static_cast<char*>(data);
    std::size_t done = 0;
    while (done < size) {
        const ssize_t n = ::read(stdout_fd_, out + done, size - done);
        if (n > 0) {
            done += std::size_t(n);
        } else if (n == 0) {
            return false;
        } else if (errno != EINTR) {
            throw IoError(std::string("reading a child process's output failed: ") + std::strerror(errno));
        }
    }
    return true;
}

std::string ChildProcess::read_all() {
    std::string text;
    char block[4096];
    for (;;) {
        const ssize_t n = ::read(stdout_fd_, block, sizeof block);
        if (n > 0) text.append(block, std::size_t(n));
        else if (n == 0 || errno != EINTR) break;
    }
    return text;
}

int ChildProcess::wait() {
    if (status_ >= 0) return status_;
    close_fd(stdout_fd_);
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0) {
        if (errno == ECHILD) {
            // SIGCHLD is ignored in this process, so the child was reaped
            // for us and its status is gone; callers check its output.
            status_ = 0;
            return status_;
        }
        if (errno != EINTR) {
            status_ = 255;
            return status_;
        }
    }
    status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return status_;
}

std::string ChildProcess::stderr_text(std::size_t max_bytes) const {
    const off_t size = ::lseek(stderr_fd_, 0, SEEK_END);
    if (size <= 0) return {};
    const off_t start = size > off_t(max_bytes) ? size - off_t(max_bytes) : 0;
    std::string text(std::size_t(size - start), '\0');
    const ssize_t n = ::pread(stderr_fd_, text.data(), text.size(), start);
    text.resize(n > 0 ? std::size_t(n) : 0);
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
    return text;
}

}  // namespace penumbra
