#include "common/fault_injection.hpp"

#include <mutex>
#include <utility>

namespace penumbra::testing {

namespace {

std::mutex injection_mutex;
std::string injection_prefix;
WorkerFailure injection = WorkerFailure::none;

std::mutex durable_mutex;
bool recording = false;
std::vector<std::string> durable_steps;
FsyncFailure fsync_failure = FsyncFailure::none;

}  // namespace

void inject_worker_failure(const std::string& stage_prefix, WorkerFailure failure) {
    std::lock_guard<std::mutex> lock(injection_mutex);
    injection_prefix = stage_prefix;
    injection = failure;
}

WorkerFailure take_worker_failure(const char* stage) {
    std::lock_guard<std::mutex> lock(injection_mutex);
    if (injection == WorkerFailure::none || std::string(stage).rfind(injection_prefix, 0) != 0)
        return WorkerFailure::none;
    const WorkerFailure armed = injection;
    injection = WorkerFailure::none;
    return armed;
}

void record_durable_steps() {
    std::lock_guard<std::mutex> lock(durable_mutex);
    recording = true;
    durable_steps.clear();
}

std::vector<std::string> recorded_durable_steps() {
    std::lock_guard<std::mutex> lock(durable_mutex);
    recording = false;
    return std::exchange(durable_steps, {});
}

void note_durable_step(const std::string& step) {
    std::lock_guard<std::mutex> lock(durable_mutex);
    if (recording) durable_steps.push_back(step);
}

void inject_fsync_failure(FsyncFailure failure) {
    std::lock_guard<std::mutex> lock(durable_mutex);
    fsync_failure = failure;
}

bool take_fsync_failure(FsyncFailure kind) {
    std::lock_guard<std::mutex> lock(durable_mutex);
    if (kind == FsyncFailure::none || fsync_failure != kind) return false;
    fsync_failure = FsyncFailure::none;
    return true;
}

}  // namespace penumbra::testing
