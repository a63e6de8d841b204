// The one parallel helper's contract (common/parallel.hpp): worker failures
// reach the caller, cancel stops every worker promptly, progress comes from
// the calling thread only, blocks do not depend on the thread count.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <new>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "common/fault_injection.hpp"
#include "common/parallel.hpp"

namespace penumbra {
namespace {

using Clock = std::chrono::steady_clock;

void busy(double seconds) {
    const auto until = Clock::now() + std::chrono::duration<double>(seconds);
    while (Clock::now() < until && !parallel_stop_requested()) {}
}

TEST(Parallel, a_workers_exception_reaches_the_caller_and_the_helper_runs_again) {
    if (resolve_threads(0) < 2) GTEST_FAIL() << "this test needs two threads";
    const auto caller = std::this_thread::get_id();
    std::atomic<bool> thrown_on_worker{false};
    auto body = [&](std::size_t, std::size_t) {
        busy(0.002);
        if (std::this_thread::get_id() != caller) {
            thrown_on_worker = true;
            throw std::bad_alloc();
        }
    };
    EXPECT_THROW(parallel_for(64, {2, 1, "test"}, body), std::bad_alloc);
    EXPECT_TRUE(thrown_on_worker);
    std::atomic<std::size_t> ran{0};
    parallel_for(1000, {0, 7, "test"}, [&](std::size_t b, std::size_t e) { ran += e - b; });
    EXPECT_EQ(ran, 1000u);
}

TEST(Parallel, the_first_of_several_failures_is_rethrown_and_later_blocks_are_skipped) {
    std::atomic<int> started{0};
    EXPECT_THROW(parallel_for(10000, {0, 1, "test"},
                              [&](std::size_t, std::size_t) {
                                  ++started;
                                  throw std::runtime_error("each block fails");
                              }),
                 std::runtime_error);
    EXPECT_LT(started.load(), 100);  // one per thread, not ten thousand
}

TEST(Parallel, cancel_stops_every_worker_within_100_ms) {
    // Blocks of 20 s each, on every thread the caller's included, that poll
    // parallel_stop_requested(); the progress callback says stop after 30 ms.
    const auto start = Clock::now();
    Clock::time_point cancelled_at;
    std::atomic<Clock::rep> last_exit{0};
    Progress progress([&](double) {
        if (Clock::now() - start < std::chrono::milliseconds(30)) return true;
        cancelled_at = Clock::now();
        return false;
    });
    EXPECT_THROW(parallel_for(64, {0, 1, "test"}, [&](std::size_t, std::size_t) {
        busy(20.0);
        const auto now = Clock::now().time_since_epoch().count();
        for (auto seen = last_exit.load(); seen < now && !last_exit.compare_exchange_weak(seen, now);) {}
    }, progress), Cancelled);
    const auto returned = Clock::now();
    ASSERT_NE(cancelled_at, Clock::time_point{});
    EXPECT_LT(returned - cancelled_at, std::chrono::milliseconds(100));
    EXPECT_LT(Clock::time_point(Clock::duration(last_exit.load())) - cancelled_at, std::chrono::milliseconds(100));
}

TEST(Parallel, progress_is_reported_from_the_calling_thread_only_and_ends_at_to) {
    const auto caller = std::this_thread::get_id();
    std::set<std::thread::id> reporters;
    std::vector<double> fractions;
    Progress progress([&](double f) {
        reporters.insert(std::this_thread::get_id());
        fractions.push_back(f);
        return true;
    });
    parallel_for(400, {0, 1, "test", 0.25, 0.75}, [](std::size_t, std::size_t) { busy(0.001); }, progress);
    EXPECT_EQ(reporters, std::set<std::thread::id>{caller});
    ASSERT_FALSE(fractions.empty());
    EXPECT_DOUBLE_EQ(fractions.back(), 0.75);
    for (double f : fractions) EXPECT_TRUE(f >= 0.25 && f <= 0.75) << f;
}

TEST(Parallel, blocks_are_fixed_by_the_block_size_not_the_threads) {
    for (int threads : {1, 2, 0}) {
        std::mutex m;
        std::vector<std::pair<std::size_t, std::size_t>> seen(block_count(103, 10));
        parallel_blocks(103, {threads, 10, "test"}, [&](std::size_t block, std::size_t b, std::size_t e) {
            std::lock_guard<std::mutex> lock(m);
            seen[block] = {b, e};
        });
        for (std::size_t k = 0; k < seen.size(); ++k)
            EXPECT_EQ(seen[k], std::make_pair(10 * k, std::min<std::size_t>(103, 10 * k + 10))) << threads;
    }
}

TEST(Parallel, the_thread_cap_is_respected) {
    std::atomic<int> now{0}, most{0};
    parallel_for(200, {1, 1, "test"}, [&](std::size_t, std::size_t) {
        most = std::max(most.load(), ++now);
        busy(0.0005);
        --now;
    });
    EXPECT_EQ(most.load(), 1);
    EXPECT_THROW(parallel_for(1, {-1, 1, "test"}, [](std::size_t, std::size_t) {}), ArgumentError);
}

TEST(Parallel, an_injected_failure_fires_once_in_the_named_stage_only) {
    testing::inject_worker_failure("tool.stage", testing::WorkerFailure::runtime_error);
    EXPECT_NO_THROW(parallel_for(100, {0, 1, "other"}, [](std::size_t, std::size_t) {}));
    EXPECT_THROW(parallel_for(100, {0, 1, "tool.stage.part"}, [](std::size_t, std::size_t) { busy(0.0005); }),
                 std::runtime_error);
    EXPECT_NO_THROW(parallel_for(100, {0, 1, "tool.stage.part"}, [](std::size_t, std::size_t) {}));
    testing::inject_worker_failure("tool", testing::WorkerFailure::bad_alloc);
    EXPECT_THROW(parallel_for(1, {0, 1, "tool.x"}, [](std::size_t, std::size_t) {}), std::bad_alloc);
}

TEST(Parallel, an_empty_loop_reports_its_end) {
    double last = -1.0;
    parallel_for(0, {0, 4, "test", 0.0, 0.5}, [](std::size_t, std::size_t) { FAIL(); },
                 Progress([&](double f) { last = f; return true; }));
    EXPECT_DOUBLE_EQ(last, 0.5);
}

}  // namespace
}  // namespace penumbra
