"""The equal-time comparison's arithmetic (issue #25), free of bpy: the
plain ramp's error read off its own curve at another render's time, and
the ratio of a method's error to it. Used by bench/helpers/
colormap_equal_time.py (in Blender) and colormap_equal_time_page.py."""

import math

import numpy as np

PLAIN = "plain"


def plain_error_at(plain, seconds, clock, error="rmse"):
    """The plain ramp's RMSE (`error`: "rmse" or "rmse_interior") at
    `seconds` of `clock` ("wall" or "cpu"), read log-log off its curve
    {spp: entry} (linear between its points in log time and log error,
    clamped at its ends). Where a render took longer than one with more
    samples (the noisy low end, where fixed costs dominate), the curve is
    the best error reached in at most that time: points that a faster one
    beats are left out."""
    frontier = []
    for t, r in sorted((max(e[clock], 1e-9), e[error]) for e in plain.values()):
        if not frontier or r < frontier[-1][1]:
            frontier.append((t, r))
    times = [math.log(t) for t, _ in frontier]
    errors = [math.log(r) for _, r in frontier]
    return float(math.exp(np.interp(math.log(max(seconds, 1e-9)), times, errors)))


def equal_time_ratios(results, method, clock, error="rmse"):
    """{spp: RMSE (`error`) of `method` / the plain ramp's at the same time}."""
    plain = results[PLAIN]
    return {spp: e[error] / plain_error_at(plain, e[clock], clock, error) for spp, e in results[method].items()}
