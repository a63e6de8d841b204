"""The 16k row of bench/lights_timing_benchmark.py, in the bpy module (a fresh
process, so that its peak RSS is its own): bpy.ops.penumbra.build_light_rig
on a 16384x8192 map, 64 lights, one frame. Prints "RESULT ms base_MB peak_MB".

    .venv/bin/python bench/blender_scripts/lights_rig_16k.py MAP.exr run"""

import os
import resource
import sys
import time
import traceback

import bpy

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))  # bench.helpers
from bench.helpers.paths import use_addon  # noqa: E402

use_addon()
import penumbra  # noqa: E402


def main(path, mode):
    penumbra.register()
    base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    t0 = time.perf_counter()
    if mode == "run":
        try:
            r = bpy.ops.penumbra.build_light_rig(filepath=path, count=64, frame_start=1, frame_end=1,
                                                 json_path=path + ".json")
            assert r == {"FINISHED"}, r
            coll = bpy.context.scene.penumbra.light_rig.collection
            assert len([o for o in coll.objects if o.type == "LIGHT"]) == 64
        except Exception:
            traceback.print_exc()
            sys.exit(1)
    t = time.perf_counter() - t0
    print("RESULT", t * 1000, base, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
    penumbra.unregister()


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
