// A small thread pool loop with the progress contract of common/progress.hpp:
// workers take chunks of an index range; the calling thread reports progress
// (and so runs the Python callback) at most every `report_seconds`, and on
// cancel or on a worker's exception stops the others and rethrows.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "common/progress.hpp"

namespace penumbra::visibility {

// 0 means every hardware thread.
inline int resolve_threads(int threads) {
    if (threads > 0) return threads;
    const unsigned n = std::thread::hardware_concurrency();
    return n ? int(n) : 1;
}

// Calls body(begin, end) for disjoint chunks covering [0, count), on
// `threads` worker threads. Progress goes from `from` to `to` as chunks finish.
inline void parallel_chunks(std::size_t count, std::size_t chunk, int threads,
                            const std::function<void(std::size_t, std::size_t)>& body, const Progress& progress,
                            double from = 0.0, double to = 1.0) {
    if (count == 0) {
        progress.report(to);
        return;
    }
    chunk = std::max<std::size_t>(1, chunk);
    const std::size_t n_chunks = (count + chunk - 1) / chunk;
    const int n_threads = int(std::min<std::size_t>(std::size_t(resolve_threads(threads)), n_chunks));
    std::atomic<std::size_t> next{0}, done{0};
    std::atomic<bool> stop{false};
    std::exception_ptr failure;
    std::mutex failure_mutex;
    auto worker = [&] {
        for (;;) {
            if (stop.load(std::memory_order_relaxed)) return;
            const std::size_t c = next.fetch_add(1);
            if (c >= n_chunks) return;
            try {
                body(c * chunk, std::min(count, (c + 1) * chunk));
            } catch (...) {
                std::lock_guard<std::mutex> lock(failure_mutex);
                if (!failure) failure = std::current_exception();
                stop = true;
                return;
            }
            done.fetch_add(1);
        }
    };
    std::vector<std::thread> pool;
    pool.reserve(n_threads);
    if (!progress.has_callback()) {
        // Nobody to report to: the calling thread works too (run-time path, no polling delay).
        for (int i = 1; i < n_threads; ++i) pool.emplace_back(worker);
        worker();
        for (auto& t : pool) t.join();
        if (failure) std::rethrow_exception(failure);
        return;
    }
    for (int i = 0; i < n_threads; ++i) pool.emplace_back(worker);
    std::exception_ptr cancelled;
    // The calling thread only watches (progress callbacks must run on it),
    // polling often so a short job ends promptly, reporting every 50 ms.
    auto last = std::chrono::steady_clock::now();
    while (done.load() < n_chunks && !stop.load()) {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        const auto now = std::chrono::steady_clock::now();
        if (now - last < std::chrono::milliseconds(50)) continue;
        last = now;
        try {
            progress.report(from + (to - from) * double(done.load()) / double(n_chunks));
        } catch (...) {
            cancelled = std::current_exception();
            stop = true;
        }
    }
    for (auto& t : pool) t.join();
    if (failure) std::rethrow_exception(failure);
    if (cancelled) std::rethrow_exception(cancelled);
    progress.report(to);
}

}  // namespace penumbra::visibility
