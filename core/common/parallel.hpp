// The core's one way to run work on several threads, on oneTBB: the scheduler
// Blender itself runs, so the two share cores instead of competing for them.
//
// parallel_blocks(count, options, body, progress) splits [0, count) into
// blocks of `options.block` indices and calls body(block, begin, end) once per
// block, on up to `options.threads` threads (0: as many as the process
// allows; a tbb::task_arena enforces the cap). The blocks depend on `block`
// alone, never on the thread count, so a reduction that keeps one partial
// result per block and sums them in block order gives the same answer on one
// thread or sixteen.
//
// Failure, cancel and progress, the contract every tool relies on:
//  - An exception from a body (std::bad_alloc included) stops the loop:
//    blocks not yet started are skipped, and the first exception is rethrown
//    on the calling thread once every running block has returned. Nothing is
//    ever thrown out of a worker thread, which would abort Blender.
//  - `progress` (common/progress.hpp) is reported from the calling thread
//    only, between the blocks that thread runs, at most every 50 ms, from
//    `options.from` to `options.to`. When it says stop (or throws), the loop
//    stops like on a failure and Cancelled is rethrown. A block that runs
//    longer than a few milliseconds should poll parallel_stop_requested()
//    and return early: cancel then reaches every worker within 100 ms.
//  - `options.stage` names the loop ("lights.region_powers"), so tests can
//    make one of its blocks fail (common/fault_injection.hpp).
#pragma once

#include <cstddef>
#include <functional>

#include "common/progress.hpp"

namespace penumbra {

struct ParallelOptions {
    int threads = 0;         // 0: as many as the process allows
    std::size_t block = 1;   // indices per block (the last block may be shorter)
    const char* stage = "";  // name for fault injection in tests
    double from = 0.0;       // progress reported from `from` ...
    double to = 1.0;         // ... to `to` as blocks finish
};

using BlockBody = std::function<void(std::size_t block, std::size_t begin, std::size_t end)>;
using RangeBody = std::function<void(std::size_t begin, std::size_t end)>;

// Number of blocks parallel_blocks() splits `count` indices into.
std::size_t block_count(std::size_t count, std::size_t block);

void parallel_blocks(std::size_t count, const ParallelOptions& options, const BlockBody& body,
                     const Progress& progress = Progress());

// The same without the block index, for loops whose blocks write disjoint outputs.
void parallel_for(std::size_t count, const ParallelOptions& options, const RangeBody& body,
                  const Progress& progress = Progress());

// Inside a body: true once the loop is stopping (a failure elsewhere, or a cancel).
bool parallel_stop_requested();

// The number of threads a loop with `threads` may use (0: the process's limit).
int resolve_threads(int threads);

}  // namespace penumbra
