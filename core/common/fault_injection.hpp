// Test hook: makes the next parallel loop of a tool fail from a worker
// thread, so tests can check that the failure reaches Python as an exception
// and that the process lives on (bound as _penumbra.testing). Not used by
// any tool; parallel_blocks() consults it once per loop.
#pragma once

#include <string>

namespace penumbra::testing {

enum class WorkerFailure { none, runtime_error, bad_alloc };

// The next loop whose stage starts with `stage_prefix` ("lights", "colormap",
// "sh", "visibility", or a full stage name) throws `failure` from one block,
// on a worker thread when the loop runs on more than one. One-shot;
// WorkerFailure::none clears a pending injection.
void inject_worker_failure(const std::string& stage_prefix, WorkerFailure failure);

// Called by parallel_blocks(): the failure armed for `stage`, consumed.
WorkerFailure take_worker_failure(const char* stage);

}  // namespace penumbra::testing
