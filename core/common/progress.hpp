// The progress/cancel contract every long operation follows.
//
// A long operation takes a `const Progress&` and calls `report(fraction)`
// between units of work, never more than a bounded amount of work apart
// (each operation documents its interval). The callback receives the fraction
// done in [0, 1] and returns true to go on or false to stop; on stop the
// operation throws penumbra::Cancelled before it changes any output the
// caller can see. The callback is always invoked from the thread that
// started the operation, so bindings can re-acquire the Python GIL safely.
#pragma once

#include <functional>
#include <utility>

#include "common/error.hpp"

namespace penumbra {

class Progress {
public:
    using Callback = std::function<bool(double fraction)>;

    Progress() = default;
    explicit Progress(Callback callback) : callback_(std::move(callback)) {}

    // Reports `fraction` done; throws Cancelled if the callback says stop.
    void report(double fraction) const {
        if (callback_ && !callback_(fraction < 0.0 ? 0.0 : (fraction > 1.0 ? 1.0 : fraction)))
            throw Cancelled();
    }

    bool has_callback() const { return static_cast<bool>(callback_); }

private:
    Callback callback_;
};

}  // namespace penumbra
