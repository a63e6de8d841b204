// A minimal fork-join loop for the light-rig tool's per-pixel work. `threads`
// follows the tool's options: 0 = every hardware thread, 1 = the caller's
// thread only (what the single-thread timings measure).
#pragma once

#include <algorithm>
#include <thread>
#include <vector>

namespace penumbra::lights {

inline int resolve_threads(int threads) {
    if (threads > 0) return threads;
    const unsigned hw = std::thread::hardware_concurrency();
    return hw == 0 ? 1 : int(hw);
}

// Calls body(begin, end) on contiguous chunks of [0, n), in parallel. Each
// chunk is its own unit: bodies must write disjoint outputs.
template <class Body>
void parallel_for(int n, int threads, Body&& body) {
    const int t = std::min(resolve_threads(threads), std::max(1, n));
    if (t <= 1 || n < 2) {
        body(0, n);
        return;
    }
    std::vector<std::thread> pool;
    pool.reserve(t - 1);
    const int chunk = (n + t - 1) / t;
    for (int i = 1; i < t; ++i) {
        const int b = i * chunk, e = std::min(n, b + chunk);
        if (b < e) pool.emplace_back([&body, b, e] { body(b, e); });
    }
    body(0, std::min(n, chunk));
    for (auto& th : pool) th.join();
}

}  // namespace penumbra::lights
