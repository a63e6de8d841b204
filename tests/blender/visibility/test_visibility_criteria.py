"""Guards issue #13's accuracy criterion, which
bench/visibility_humanoid_benchmark.py checks on the realistic character at
10k vertices over 64 frames: on frames held out of the training, the pose
model's mean |ΔAO| against Cycles' AO bake of those frames is at most 1.5×
that of a per-frame bake of them at the same 128 rays. Here the same
character small: 2.5k vertices (detail 0.25), 32 frames (the benchmark's
--quick count), every 4th held out (8) and 24 training, 2 lobes, order 4,
Cycles at 128 samples; built, baked and fitted by the benchmark's own code
and judged by its definition (bench/helpers/visibility_criteria.py).
Measured 1.18×. (The procedural character, examples/scenes/visibility_character.py,
does not meet it: 1.7× over 48 frames, 2.1× over 24; the criterion is the
realistic character's.)

Shown able to fail: the criterion rejects the pose-ignoring model (the
training frames' mean visibility: the benchmark's ceiling) on the same
frames, measured 2.4×. Runs in bpy 4.5 only (conftest.py's ONLY_IN
collects it there and nowhere else), the Blender the benchmark runs in."""

import pytest

from bench import visibility_humanoid_benchmark as humanoid  # its character, fit and Cycles settings
from bench.helpers.cycles_ao import cycles_ao
from bench.helpers.visibility_criteria import GOAL, held_out_errors, over_per_frame
from bench.helpers.visibility_training import bake_frames, model_sh

DETAIL, FRAMES = 0.25, 32
HELD_OUT = list(range(4, FRAMES + 1, 4))


@pytest.fixture(scope="module")
def errors():
    """held_out_errors() of the model fitted on the other frames."""
    import penumbra
    from penumbra import native
    from penumbra.visibility import armature_data, frame_shading
    core = native.require()
    penumbra.register()
    try:
        obj, rig, _ = humanoid.new_humanoid(DETAIL, FRAMES)
        training = bake_frames(obj, [f for f in range(1, FRAMES + 1) if f not in HELD_OUT],
                               humanoid.RAYS, humanoid.ORDER).training
        model, _, _ = humanoid.fit(core, training, armature_data.bone_influence(obj, rig))
        held_out = bake_frames(obj, HELD_OUT, humanoid.RAYS, humanoid.ORDER).training
        cycles, _ = cycles_ao(obj, HELD_OUT, humanoid.CYCLES_SAMPLES)
        return held_out_errors(core, model_sh(model, held_out), training, held_out, cycles)
    finally:
        frame_shading.forget()
        penumbra.unregister()


@pytest.mark.parametrize("model, meets", [("model", True), ("pose_ignoring", False)],
                         ids=["pose model", "pose-ignoring model"])
def test_held_out_error_is_within_1_5x_of_the_per_frame_bakes(errors, model, meets):
    assert (over_per_frame(errors, model) <= GOAL) == meets, errors
