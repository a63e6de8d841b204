#include "common/parallel.hpp"

#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <mutex>
#include <new>
#include <stdexcept>
#include <thread>

#include "common/fault_injection.hpp"

namespace penumbra {

namespace {

class Loop;
thread_local Loop* current_loop = nullptr;

// Everything one loop's blocks share.
class Loop {
public:
    Loop(std::size_t count, const ParallelOptions& options, const BlockBody& body, const Progress& progress)
        : count_(count), options_(options), body_(body), progress_(progress),
          blocks_(block_count(count, options.block)), caller_(std::this_thread::get_id()),
          injected_(testing::take_worker_failure(options.stage)), last_report_(std::chrono::steady_clock::now()) {}

    std::size_t blocks() const { return blocks_; }

    void run_block(std::size_t b, bool single_thread) {
        if (stop_.load(std::memory_order_relaxed)) return;
        const bool on_caller = std::this_thread::get_id() == caller_;
        Loop* outer = current_loop;
        current_loop = this;
        try {
            if (injected_ != testing::WorkerFailure::none && (single_thread || !on_caller) &&
                !injection_done_.exchange(true))
                throw_injected();
            const std::size_t begin = b * options_.block;
            body_(b, begin, std::min(count_, begin + options_.block));
            done_.fetch_add(1, std::memory_order_relaxed);
            if (on_caller) report_if_due();
        } catch (...) {
            fail(std::current_exception());
        }
        current_loop = outer;
    }

    // parallel_stop_requested() from inside a body. On the calling thread it
    // is also a chance to report progress, so a long block there does not
    // hold up a cancel.
    bool stop_requested() {
        if (std::this_thread::get_id() == caller_ && !stop_.load(std::memory_order_relaxed)) {
            try {
                report_if_due();
            } catch (...) {
                fail(std::current_exception());
            }
        }
        return stop_.load(std::memory_order_relaxed);
    }

    // After the loop, on the calling thread.
    void finish() {
        if (failure_) std::rethrow_exception(failure_);
        // A loop too small to reach a worker still fails as asked.
        if (injected_ != testing::WorkerFailure::none && !injection_done_) throw_injected();
        progress_.report(options_.to);
    }

private:
    void report_if_due() {
        if (!progress_.has_callback()) return;
        const auto now = std::chrono::steady_clock::now();
        if (now - last_report_ < std::chrono::milliseconds(50)) return;
        last_report_ = now;
        const double f = double(done_.load(std::memory_order_relaxed)) / double(blocks_);
        progress_.report(options_.from + (options_.to - options_.from) * f);  // may throw Cancelled
    }

    void fail(std::exception_ptr e) {
        std::lock_guard<std::mutex> lock(failure_mutex_);
        if (!failure_) failure_ = e;
        stop_.store(true, std::memory_order_relaxed);
    }

    [[noreturn]] void throw_injected() const {
        if (injected_ == testing::WorkerFailure::bad_alloc) throw std::bad_alloc();
        throw std::runtime_error(std::string("failure injected by a test into '") + options_.stage + "'");
    }

    const std::size_t count_;
    const ParallelOptions& options_;
    const BlockBody& body_;
    const Progress& progress_;
    const std::size_t blocks_;
    const std::thread::id caller_;
    const testing::WorkerFailure injected_;
    std::atomic<bool> injection_done_{false};
    std::atomic<bool> stop_{false};
    std::atomic<std::size_t> done_{0};
    std::chrono::steady_clock::time_point last_report_;  // touched by the caller only
    std::mutex failure_mutex_;
    std::exception_ptr failure_;
};

}  // namespace

std::size_t block_count(std::size_t count, std::size_t block) {
    block = std::max<std::size_t>(1, block);
    return (count + block - 1) / block;
}

int resolve_threads(int threads) {
    const int allowed = int(std::min<std::size_t>(
        tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism),
        std::size_t(tbb::info::default_concurrency())));
    return std::max(1, threads > 0 ? std::min(threads, allowed) : allowed);
}

bool parallel_stop_requested() {
    return current_loop && current_loop->stop_requested();
}

void parallel_blocks(std::size_t count, const ParallelOptions& options, const BlockBody& body,
                     const Progress& progress) {
    if (options.threads < 0)
        throw ArgumentError("threads must be >= 0 (0 = all cores), got " + std::to_string(options.threads));
    ParallelOptions checked = options;
    checked.block = std::max<std::size_t>(1, options.block);
    Loop loop(count, checked, body, progress);
    const int threads = std::min<std::size_t>(std::size_t(resolve_threads(options.threads)), loop.blocks());
    if (threads <= 1) {
        for (std::size_t b = 0; b < loop.blocks(); ++b) loop.run_block(b, true);
    } else {
        // The arena caps the threads; the calling thread works in it too,
        // which is where progress is reported from.
        tbb::task_arena arena(threads);
        arena.execute([&] {
            tbb::parallel_for(std::size_t(0), loop.blocks(), [&](std::size_t b) { loop.run_block(b, false); });
        });
    }
    loop.finish();
}

void parallel_for(std::size_t count, const ParallelOptions& options, const RangeBody& body,
                  const Progress& progress) {
    parallel_blocks(count, options, [&](std::size_t, std::size_t begin, std::size_t end) { body(begin, end); },
                    progress);
}

}  // namespace penumbra
