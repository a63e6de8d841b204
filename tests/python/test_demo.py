"""`make demo` (examples/demo.py) in its quick mode, in all three Blenders:
it prints one line per step and a closing table and nothing else (Blender's
render progress goes to the log), well under 200 lines, and writes one
labelled contact sheet per tool, at least 1200 pixels wide, whose measured
errors say what the README says (and, in bpy 5.2, EEVEE's beside Cycles'),
and the sidebar's screenshot. The quick
mode runs every step of the full demo with smaller pictures and fewer
samples, so the full run prints the same lines (the line count depends on
the steps, not the sizes)."""

import glob
import json
import os
import subprocess
import sys

import pytest

from tests import rig_json_schema

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEMO = os.path.join(ROOT, "examples", "demo.py")
BLENDERS = ("blender-3.4", "bpy-4.5", "bpy-5.2")
SHEETS = ("visibility", "lights", "colormap")
STEPS = ["image I/O", "visibility model", "visibility sheet", "light rig", "lights sheet", "animated rig",
         "colour-map lookup", "colour-map sheet"]
MAX_PRINTED_LINES = 200
GPU_BLENDER = "bpy-5.2"  # the Blender whose demo reads the GPU preview back (after gpu.init())

@pytest.fixture(scope="module")
def quick_demo(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)
    proc = subprocess.run([sys.executable, DEMO, "--quick", "--out", str(out)], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=1800)
    assert proc.returncode == 0, f"{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    summaries = {}
    for name in BLENDERS:
        with open(os.path.join(out, name, "summary.json")) as f:
            summaries[name] = json.load(f)
    return out, proc.stdout.splitlines(), summaries


def test_demo_prints_a_line_per_step_and_a_table_and_nothing_from_blender(quick_demo):
    out, lines, summaries = quick_demo
    assert len(lines) < MAX_PRINTED_LINES
    # Blender's own output (render progress, operator reports) is in the log only.
    assert not [line for line in lines if "Fra:" in line or "Sample" in line or line.startswith("Info:")]
    with open(os.path.join(out, "demo.log")) as f:
        log = f.read()
    assert "Fra:" in log and all(f"===== {name}:" in log for name in BLENDERS)
    for name in BLENDERS:
        assert [s["step"] for s in summaries[name]["steps"]] == STEPS
        # Blender 3.4 also takes the panel screenshot, in a window under Xvfb.
        steps = STEPS + (["panel screenshot"] if name == "blender-3.4" else [])
        step_lines = [line for line in lines if line.startswith("  " + name) and ": " in line]
        assert len(step_lines) == len(steps), step_lines
        # The closing table: a row per step and one for the whole run.
        rows = [line for line in lines if line.startswith(name + " ")]
        assert [r.split("  ")[0] for r in rows] == [name] * (len(steps) + 1)
        assert all(s in " ".join(rows) for s in steps)


def test_demo_writes_a_wide_contact_sheet_per_tool_and_the_panel_screenshot(quick_demo):
    out, _, _ = quick_demo
    sys.path.insert(0, os.path.join(ROOT, "build", "addon", "penumbra"))
    import _penumbra
    for name in (*BLENDERS, ""):
        for tool in SHEETS:
            path = os.path.join(out, name, f"{tool}-sheet.png")
            assert _penumbra.image.read_info(path)["width"] >= 1200, path
    assert os.path.exists(os.path.join(out, "panel.png"))


def test_the_demos_rig_files_follow_the_documented_schema(quick_demo):
    out, _, _ = quick_demo
    for name in BLENDERS:
        paths = sorted(glob.glob(os.path.join(out, name, "*", "rig_*.json")))
        assert [os.path.basename(p) for p in paths] == ["rig_animated.json", "rig_static.json"], name
        for path in paths:
            with open(path) as f:
                rig_json_schema.validate(json.load(f))


def test_demo_errors_say_what_the_readme_says(quick_demo):
    """Thresholds for the quick mode's few samples, with a margin: measured
    mean |ΔAO| 0.008–0.011, render RMSE 3.5–7 %, colour-map RMSE 0.245
    plain → 0.041 Penumbra at 1 spp."""
    out, _, summaries = quick_demo
    for name, summary in summaries.items():
        visibility = summary["visibility"]
        assert all(p["mean_abs"] < 0.03 for p in visibility["unseen_poses_vs_cycles_ao"]), name
        # The GPU preview's readback of an unseen pose against the CPU shading
        # (issue 27's tolerance); the other Blenders' sheets say why it did not run.
        gpu = visibility["gpu_preview_vs_cpu"]
        if name == GPU_BLENDER:
            assert gpu["max_abs"] < 1e-3 and gpu["vertices"] > 0 and gpu["preview_cpu_ms_per_frame"] > 0, gpu
        else:
            assert gpu["not_run"].startswith("no GPU available"), (name, gpu)
        lights = summary["light_rig"]["static"]
        assert lights["suns"] == 64 and lights["render_relative_rmse"] < 0.15, name
        assert abs(lights["render_mean_ratio"] - 1.0) < 0.05, name
        # EEVEE draws where it has a GPU context: the bpy 5.2 module after
        # gpu.init(). Measured in quick mode (4 samples): World 15.8 %, mean
        # 0.961; the 32-sun rig built for EEVEE 18.2 %, mean 0.905 (no bounce light).
        assert ("eevee" in lights) == (name == "bpy-5.2"), name
        rmse = summary["colormap"]["rmse"]
        assert rmse["Penumbra filtered ramp 1 spp"] < 0.5 * rmse["plain ramp 1 spp"], name
        # The sheet sets the filtered ramp beside the plain ramp rendered for
        # the same time (issue #25): a sample count whose render took about as
        # long, with both errors printed (who wins is the benchmark's to say).
        equal = summary["colormap"]["equal_time"]
        assert equal["plain"]["spp"] > equal["filtered"]["spp"], (name, equal)
        assert 0.5 < equal["plain"]["seconds"] / equal["filtered"]["seconds"] < 2.0, (name, equal)
    eevee = summaries["bpy-5.2"]["light_rig"]["static"]["eevee"]
    # The rig shown is one EEVEE draws whole: 64 suns overflowed EEVEE Next's
    # factory shadow pool, which then drops shadows and prints this.
    with open(os.path.join(out, "demo.log")) as f:
        assert "Shadow buffer full" not in f.read()
    for lit_by in ("world", "rig"):
        assert eevee[lit_by]["render_relative_rmse"] < 0.3, lit_by
        assert 0.85 < eevee[lit_by]["render_mean_ratio"] < 1.05, lit_by
    # What the sheet shows of the gap: Cycles without bounce light is that
    # much darker than the World render, and EEVEE's rig matches it (the
    # make-test check's 4 %). Measured in quick mode: 0.890 and 1.017.
    assert eevee["cycles_direct_mean_ratio"] < 0.95, eevee
    assert abs(eevee["rig_vs_direct"]["render_mean_ratio"] - 1.0) < 0.04, eevee
