"""Issue #13's accuracy criterion of the visibility pose model: on frames
held out of its training, its AO error against Cycles' AO bake of the same
frames is at most GOAL times the error of a per-frame bake of those frames
at the same rays (the floor the model can approach). Beside them, the
pose-ignoring model (the training frames' mean visibility: the ceiling).
Shared by bench/visibility_humanoid_benchmark.py (the realistic character
at 10k vertices, 64 frames) and tests/blender/visibility/test_visibility_criteria.py
(the same character small)."""

import numpy as np

from bench.helpers.visibility_training import baked_sh

GOAL = 1.5


def frame_ao(core, sh_frames):
    """(V, frames) AO of SH visibility (frames, V, order²)."""
    return np.stack([core.visibility.ambient_occlusion(f) for f in sh_frames], axis=1)


def against(reference, ao):
    """Mean |Δ| and correlation of two (V, frames) AO arrays."""
    return {"mean_abs": float(np.abs(ao - reference).mean()),
            "correlation": float(np.corrcoef(ao.ravel(), reference.ravel())[0, 1])}


def held_out_errors(core, model_sh, training, held_out, cycles_ao):
    """{"model", "per_frame", "pose_ignoring": against(cycles_ao, ...),
    "model_vs_per_frame"}: `model_sh` is the model's SH visibility (frames,
    V, order²) at the poses of the TrainingSet `held_out`, which holds the
    per-frame bake of those frames; `training` the frames the model was fitted
    on; `cycles_ao` (V, frames) Cycles' AO bake of the held-out frames."""
    truth = baked_sh(held_out)
    mean_sh = baked_sh(training).mean(axis=0)
    ao = {"model": frame_ao(core, model_sh),
          "per_frame": frame_ao(core, truth),
          "pose_ignoring": np.repeat(core.visibility.ambient_occlusion(mean_sh)[:, None], len(held_out), axis=1)}
    errors = {name: against(cycles_ao, x) for name, x in ao.items()}
    errors["model_vs_per_frame"] = against(ao["per_frame"], ao["model"])
    return errors


def over_per_frame(errors, model="model"):
    """`model`'s held-out error / the per-frame bake's (the criterion: <= GOAL)."""
    return errors[model]["mean_abs"] / errors["per_frame"]["mean_abs"]
