"""The visibility bake driven on an explicit list of frames, as the
benchmarks and tests drive it, and the SH visibility a fitted pose model
predicts for those frames' poses. Inside Blender (bpy), with the add-on
importable (build/addon on sys.path) and registered."""

import collections
import time

import bpy
import numpy as np

from penumbra import native
from penumbra.visibility import bake

# training: the TrainingSet; seconds: posing, reading and tracing the frames;
# setup_seconds: making the job; job: the BakeJob (job.seconds splits the
# time, job.rays_cast, job.seconds_trace).
BakedFrames = collections.namedtuple("BakedFrames", "training seconds setup_seconds job")


def bake_frames(obj, frames, rays, order=4, overlap=False, occluders=None, below_horizon="occluded"):
    """Bakes the active character `obj` at each of `frames` (any list: the
    operator takes a range) in one job, as the operator bakes: read a frame,
    then trace it, or with `overlap` read the next frame while tracing
    (penumbra.visibility.bake.bake_frames). Returns BakedFrames."""
    started = time.perf_counter()
    job = bake.BakeJob(bpy.context, obj, frames[0], frames[0], 1, rays, 1, order, occluders, below_horizon)
    job.frames = [(None, f) for f in frames]
    setup = time.perf_counter() - started
    started = time.perf_counter()
    try:
        bake.bake_frames(job, overlap=overlap)
    finally:
        job.restore_frame()
    return BakedFrames(job.training, time.perf_counter() - started, setup, job)


def model_sh(model, training):
    """The SH visibility (frames, V, order²) `model` predicts at the poses of
    `training`'s frames (its bone rotations; the visibility is not used)."""
    core = native.require()
    joints = [training.bone_names.index(j) for j in model.joints]
    out = []
    for i in range(len(training)):
        _, _, params = model.synthesize(training.bone_rotations(i)[joints])
        out.append(core.visibility.zh_params_to_sh(params.astype(np.float64)))
    return np.stack(out)


def baked_sh(training):
    """The SH visibility (frames, V, order²) baked into `training`."""
    return np.stack([training.visibility(i).astype(np.float64) for i in range(len(training))])
