"""The "Last bake" lines of the visibility panel, from the JSON summary a
bake stores on the object (`penumbra_visibility.report`). No bpy here: the
report comes from a .blend file, so it is outside data and may hold
anything (a report from another version, a hand-edited or damaged file);
tests/fuzz/python/fuzz_bake_report.py fuzzes it. A panel's draw that raises
breaks the panel on every redraw, so nothing here may raise."""

import json
import math

DAMAGED = "The stored bake report is unreadable; bake again to refresh it"


def _number(value):
    """A finite int or float (not a bool), else None."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    try:
        value = float(value)
    except OverflowError:  # an int too large for a float
        return None
    return value if math.isfinite(value) else None


def _field(summary, *path):
    """summary[path[0]][path[1]]..., a number, or None when absent or not a number."""
    value = summary
    for key in path:
        if not isinstance(value, dict) or key not in value:
            return None
        value = value[key]
    return _number(value)


def summary_lines(report):
    """The panel's lines for `report` (a JSON string): [] when there is no
    summary (or no JSON), one line saying so when the JSON is not a bake summary."""
    if not isinstance(report, str) or not report:
        return []
    try:
        summary = json.loads(report)
    except (ValueError, RecursionError):  # not JSON, or nested too deep for the parser
        return []
    if not summary:
        return []
    if not isinstance(summary, dict):
        return [DAMAGED]
    numbers = {key: _field(summary, key) for key in
               ("frames", "rays", "lobes", "model_bytes", "dense_bytes", "seconds_bake", "seconds_fit")}
    sh_rms = _field(summary, "zh_fit", "sh_rms")
    joints = summary.get("active_joints")
    if any(v is None for v in numbers.values()) or sh_rms is None or not isinstance(joints, list) or \
            not all(isinstance(j, str) for j in joints):
        return [DAMAGED]
    lines = [
        f"{numbers['frames']:.0f} frames, {numbers['rays']:.0f} rays, {numbers['lobes']:.0f} lobes",
        f"Active joints: {', '.join(joints) or 'none'}",
        f"ZH fit error (RMS): {sh_rms:.4f}",
    ]
    holdout = _field(summary, "model_holdout", "ao_mean_abs")
    if summary.get("holdout_frames") and holdout is not None:
        lines.append(f"Held-out AO error (saved model): {holdout:.4f}")
    else:
        lines.append("No held-out frames (bake 8 or more)")
    lines.append(f"Model {numbers['model_bytes'] / 1e6:.2f} MB (dense {numbers['dense_bytes'] / 1e6:.2f} MB)")
    lines.append(f"Bake {numbers['seconds_bake']:.1f} s, fit {numbers['seconds_fit']:.1f} s")
    return lines
