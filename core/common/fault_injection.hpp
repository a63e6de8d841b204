// Test hooks, not used by any tool (bound as _penumbra.testing):
//  - a failure injected into the next parallel loop of a tool, thrown from a
//    worker thread, so tests can check that it reaches Python as an exception
//    and that the process lives on (parallel_blocks() consults it once per
//    loop);
//  - the steps of durable writes (common/durable_file.hpp) recorded in order,
//    and an fsync made to fail, so tests can check that a file is flushed
//    before it is published and its folder after, and what a failed flush
//    leaves behind.
#pragma once

#include <string>
#include <vector>

namespace penumbra::testing {

enum class WorkerFailure { none, runtime_error, bad_alloc };

// The next loop whose stage starts with `stage_prefix` ("lights", "colormap",
// "sh", "visibility", or a full stage name) throws `failure` from one block,
// on a worker thread when the loop runs on more than one. One-shot;
// WorkerFailure::none clears a pending injection.
void inject_worker_failure(const std::string& stage_prefix, WorkerFailure failure);

// Called by parallel_blocks(): the failure armed for `stage`, consumed.
WorkerFailure take_worker_failure(const char* stage);

// Starts recording durable-write steps, forgetting any recorded before. The
// steps read "fsync file <path>", "rename <from> -> <to>" and
// "fsync folder <folder>", each noted just before it is taken.
void record_durable_steps();

// The steps recorded since record_durable_steps(); recording stops.
std::vector<std::string> recorded_durable_steps();

// Called by durable_file.cpp before each step.
void note_durable_step(const std::string& step);

enum class FsyncFailure { none, file, folder };

// The next fsync of a file or of a folder by a durable write fails with EIO,
// as a dying disk's would. One-shot; FsyncFailure::none clears it.
void inject_fsync_failure(FsyncFailure failure);

// Called by durable_file.cpp before an fsync of `kind` (file or folder):
// whether it is to fail, consumed.
bool take_fsync_failure(FsyncFailure kind);

}  // namespace penumbra::testing
