"""The GPU viewport preview's shading against the CPU's, per vertex, once per
`make test` (tests/blender/visibility/test_gpu_preview.py covers the rest of the
preview in every Blender, headless): tests/blender/visibility/gpu_preview_check.py in
Debian's Blender 3.4 in a real window under Xvfb (Mesa's llvmpipe, OpenGL
4.5), and in the bpy 5.2 module after gpu.init() (EGL, the same llvmpipe).
These need only the `blender`, `xvfb-run` and .venv313 programs that
scripts/install_deps.sh installs. The frame time at 100k vertices is
measured by bench/visibility_gpu_preview_benchmark.py, not here."""

import os
import shutil
import subprocess

from bench.helpers.result_line import only_result

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
CHECK = os.path.join(ROOT, "tests", "blender", "visibility", "gpu_preview_check.py")
# The goal: GPU and CPU shading of a vertex differ by at most this (absolute,
# scene-linear; measured ~1e-5, float rounding).
GPU_TOLERANCE = 1e-3


def run_check(command, capsys, what, timeout=1500):
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)
    proc = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True, timeout=timeout)
    result = only_result(proc)
    assert result["ok"], result.get("error")
    with capsys.disabled():
        print(f"\n{what}: {result['renderer']}")
        pipeline, sweep = result["pipeline"], result["random"]
        print(f"  {pipeline['vertices']} vertices, 3 unseen poses x 3 BRDFs: max |GPU - CPU| "
              f"rgb {pipeline['max_abs_rgb']:.2e}, visibility {pipeline['max_abs_visibility']:.2e}")
        print(f"  {sweep['configurations']} configurations (orders, lobes, BRDFs), random data: "
              f"max |GPU - CPU| {sweep['max_abs']:.2e} ({sweep['max_relative']:.2e} relative)")
        for t in result["timing"]:
            print(f"  frame time at {t['vertices']} vertices: {t['frame_ms']:.1f} ms = CPU {t['cpu_ms']:.1f} "
                  f"(read {t['cpu_split_ms']['read']:.1f}, pose->lobes {t['cpu_split_ms']['pose_to_lobes']:.1f}, "
                  f"frames {t['cpu_split_ms']['frames']:.1f}, pack {t['cpu_split_ms']['pack']:.1f}) "
                  f"+ upload {t['upload_ms']:.1f} + draw 1280x720 {t['gpu_draw_1280x720_ms']:.1f}; "
                  f"per-vertex shading + readback {t['gpu_shade_readback_ms']:.1f} ms")
            if "viewport" in t:
                v = t["viewport"]
                print(f"    viewport {v['region'][0]}x{v['region'][1]}: redraw {v['redraw_preview_off_ms']:.0f} ms "
                      f"preview off, {v['redraw_preview_on_ms']:.0f} ms on; frame change + redraw "
                      f"{v['frame_change_and_redraw_ms']:.0f} ms")
    return result


def check_result(result):
    pipeline, sweep = result["pipeline"], result["random"]
    assert result["unavailable"] is None
    assert 9000 <= pipeline["vertices"] <= 11000
    assert pipeline["max_abs_rgb"] <= GPU_TOLERANCE
    assert pipeline["max_abs_visibility"] <= GPU_TOLERANCE
    assert pipeline["max_abs_attributes"] <= GPU_TOLERANCE
    # Non-trivial shading was compared (an environment with a sun; Phong highlights).
    assert all(case["rgb_max"] > 0.5 for case in pipeline["cases"])
    assert sweep["max_abs"] <= GPU_TOLERANCE
    assert sweep["invalid_vertices"] > 0  # invalid vertices were exercised: 0 on both sides


def test_gpu_shading_matches_the_cpu_in_blender_3_4_under_xvfb(capsys):
    blender, xvfb = shutil.which("blender"), shutil.which("xvfb-run")
    assert blender and xvfb, "Debian's blender and xvfb-run are installed by scripts/install_deps.sh"
    result = run_check([xvfb, "-a", blender, "--factory-startup", "--python", CHECK, "--",
                        "--vertices", "10000", "--sweep", "full"],
                       capsys, "Blender 3.4, window under Xvfb")
    assert result["blender"].startswith("3.4") and not result["background"]
    check_result(result)
    assert result["random"]["configurations"] == 8 * 4 * 3
    # The preview was drawn by Blender's own viewport, through the draw callback.
    assert all(t["viewport"]["drawn"] and t["viewport"]["status"] == "" for t in result["timing"])


def test_gpu_shading_matches_the_cpu_in_the_bpy_5_2_module_with_gpu_init(capsys):
    python = os.path.join(ROOT, ".venv313", "bin", "python")
    assert os.path.exists(python), "the bpy 5.2 module is installed by scripts/install_deps.sh"
    result = run_check([python, CHECK, "--gpu-init", "--vertices", "10000", "--sweep", "production"],
                       capsys, "bpy 5.2 module, gpu.init() (EGL)")
    assert result["blender"].startswith("5.2") and result["background"]
    check_result(result)
