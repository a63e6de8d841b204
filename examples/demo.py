#!/usr/bin/env python3
"""Penumbra's demo, headless: runs examples/demo_blender.py inside the three
Blenders (Debian's `blender` 3.4, the bpy 4.5 module in .venv and the bpy
5.2 module in .venv313) and writes everything under --out (default out/).
`make demo` calls this.

Prints one line per step as it finishes and a closing table (what was made,
its error against the reference, the time); everything the Blenders print
(render progress, reports) goes to <out>/demo.log (<out>/panel.log for the
screenshot). Each Blender writes its pictures, one contact sheet per tool
and summary.json under <out>/<blender>/; the newest Blender's sheets are
copied to <out>/<tool>-sheet.png. Last, examples/panel_screenshot.py
photographs the Penumbra sidebar in Blender 3.4 under Xvfb: <out>/panel.png.

    .venv/bin/python examples/demo.py [--out out] [--quick] [--blenders bpy-4.5,bpy-5.2] [--docs]

--quick: smaller pictures and fewer samples, every step still run (the
test of the demo uses it). --docs: also writes 1000-pixel-wide copies of the
sheets to docs/demo/ and the screenshot to docs/panel.png, for the README."""

import argparse
import json
import os
import shutil
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPT = os.path.join(ROOT, "examples", "demo_blender.py")
STEP_PREFIX = "demo step: "  # demo_blender.py starts each step's line with it
SHEETS = ("visibility", "lights", "colormap")
DOCS_WIDTH = 1000


def blenders(out, quick):
    """(name, command) for each Blender, oldest first."""
    extra = ["--quick"] if quick else []
    runs = []
    blender = shutil.which("blender")
    if blender:
        runs.append(("blender-3.4", [blender, "-b", "--factory-startup", "--python-exit-code", "1",
                                     "--python", SCRIPT, "--", "--out", os.path.join(out, "blender-3.4"), *extra]))
    else:
        runs.append(("blender-3.4", None))
    for name, venv in (("bpy-4.5", ".venv"), ("bpy-5.2", ".venv313")):
        python = os.path.join(ROOT, venv, "bin", "python")
        command = [python, SCRIPT, "--out", os.path.join(out, name), *extra] if os.path.exists(python) else None
        runs.append((name, command))
    return runs


def step_line(name, step):
    error = f" | {step['error']}" if step["error"] else ""
    return f"  {name:<11} {step['step']}: {step['made']}{error} | {step['seconds']:.1f} s"


def run_one(name, command, log):
    """Runs one Blender, its output into `log`, printing its step lines.
    Returns (ok, seconds, last lines of its output)."""
    log.write(f"\n===== {name}: {' '.join(command)}\n")
    log.flush()
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)
    started = time.perf_counter()
    tail = []
    with subprocess.Popen(command, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True, errors="replace", bufsize=1) as child:
        for line in child.stdout:
            log.write(line)
            tail = (tail + [line.rstrip()])[-15:]
            if line.startswith(STEP_PREFIX):
                print(step_line(name, json.loads(line[len(STEP_PREFIX):])), flush=True)
    log.flush()
    return child.returncode == 0, time.perf_counter() - started, tail


def panel_screenshot(out):
    """The sidebar photographed in Blender 3.4 under Xvfb
    (examples/panel_screenshot.py). Returns its step, or None if it failed."""
    sys.path.insert(0, os.path.join(ROOT, "examples"))
    import panel_screenshot as screenshot
    started = time.perf_counter()
    path = os.path.join(out, "panel.png")
    try:
        screenshot.screenshot(path, log_path=os.path.join(out, "panel.log"))
    except RuntimeError as error:
        print(f"  {'blender-3.4':<11} panel screenshot FAILED: {error}", flush=True)
        return None
    step = {"step": "panel screenshot", "made": "panel.png: the Penumbra sidebar at its default width",
            "error": "", "seconds": round(time.perf_counter() - started, 2)}
    print(step_line("blender-3.4", step), flush=True)
    return step


def table(results, extra_steps):
    """The closing table: one row per step of every Blender that ran, then
    `extra_steps` ((Blender, step) pairs)."""
    rows = [("Blender", "step", "made", "error vs reference", "time")]
    for name, summary, seconds in results:
        for s in summary.get("steps", []):
            rows.append((name, s["step"], s["made"], s["error"] or "-", f"{s['seconds']:.1f} s"))
        rows.append((name, "whole run", f"Blender {summary.get('blender', '?')}", "", f"{seconds:.0f} s"))
    for name, s in extra_steps:
        rows.append((name, s["step"], s["made"], s["error"] or "-", f"{s['seconds']:.1f} s"))
    widths = [max(len(r[k]) for r in rows) for k in range(len(rows[0]))]
    lines = []
    for i, row in enumerate(rows):
        cells = [c.ljust(w) if k < 4 else c.rjust(w) for k, (c, w) in enumerate(zip(row, widths))]
        lines.append("  ".join(cells).rstrip())
        if i == 0:
            lines.append("  ".join("-" * w for w in widths))
    return lines


def copy_sheets(out, names, docs):
    """The newest Blender's sheets to <out>/<tool>-sheet.png (and small
    copies to docs/demo/, and the screenshot to docs/). Returns the Blender
    the sheets came from."""
    if docs and os.path.exists(os.path.join(out, "panel.png")):
        shutil.copyfile(os.path.join(out, "panel.png"), os.path.join(ROOT, "docs", "panel.png"))
    source = next((n for n in reversed(names)
                   if all(os.path.exists(os.path.join(out, n, f"{t}-sheet.png")) for t in SHEETS)), None)
    if source is None:
        return None
    for tool in SHEETS:
        shutil.copyfile(os.path.join(out, source, f"{tool}-sheet.png"), os.path.join(out, f"{tool}-sheet.png"))
    if docs:
        sys.path.insert(0, os.path.join(ROOT, "build", "addon", "penumbra"))
        sys.path.insert(0, os.path.join(ROOT, "examples"))
        import _penumbra
        import contact_sheet
        folder = os.path.join(ROOT, "docs", "demo")
        os.makedirs(folder, exist_ok=True)
        for tool in SHEETS:
            sheet = _penumbra.image.read(os.path.join(out, f"{tool}-sheet.png"))
            # Rounded to 8-bit levels: the 16-bit PNG then compresses to about half.
            small = (contact_sheet.resize(sheet, DOCS_WIDTH).clip(0.0, 1.0) * 255.0).round() / 255.0
            _penumbra.image.write_png16(os.path.join(folder, f"{tool}-sheet.png"), small, "sRGB")
    return source


def run_blenders(out, wanted, quick, log_path):
    """Runs the demo in each wanted Blender; returns ([(name, summary,
    seconds)], [names that failed])."""
    results, failed = [], []
    with open(log_path, "w") as log:
        for name, command in blenders(out, quick):
            if name not in wanted:
                continue
            if command is None:
                print(f"  {name:<11} missing: run scripts/install_deps.sh (make demo does)", flush=True)
                failed.append(name)
                continue
            ok, seconds, tail = run_one(name, command, log)
            summary_path = os.path.join(out, name, "summary.json")
            if not ok or not os.path.exists(summary_path):
                print(f"  {name:<11} FAILED after {seconds:.0f} s; its last lines (all of it in {log_path}):")
                print("\n".join(f"    {line}" for line in tail), flush=True)
                failed.append(name)
                continue
            with open(summary_path) as f:
                results.append((name, json.load(f), seconds))
            print(f"  {name:<11} done in {seconds:.0f} s", flush=True)
    return results, failed


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default=os.path.join(ROOT, "out"))
    parser.add_argument("--quick", action="store_true", help="small pictures, few samples, every step")
    parser.add_argument("--blenders", default="blender-3.4,bpy-4.5,bpy-5.2",
                        help="which Blenders to run, comma-separated")
    parser.add_argument("--docs", action="store_true",
                        help="also write small copies of the sheets to docs/demo/ and the screenshot to docs/")
    args = parser.parse_args()
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    wanted = args.blenders.split(",")
    log_path = os.path.join(out, "demo.log")
    print(f"demo{' (quick)' if args.quick else ''}: writing {out}; the Blenders' own output goes to {log_path}",
          flush=True)

    results, failed = run_blenders(out, wanted, args.quick, log_path)
    extra_steps = []
    if "blender-3.4" in wanted:
        step = panel_screenshot(out)
        if step is None:
            failed.append("blender-3.4 (panel screenshot)")
        else:
            extra_steps.append(("blender-3.4", step))

    print()
    print("\n".join(table(results, extra_steps)))
    source = copy_sheets(out, [name for name, _, _ in results], args.docs)
    if source:
        where = " (copies in docs/demo/ and docs/panel.png)" if args.docs else ""
        print(f"\ncontact sheets from {source} in {out}{where}: "
              + ", ".join(f"{t}-sheet.png" for t in SHEETS))
    if failed:
        sys.exit(f"demo failed in: {', '.join(failed)} (see {log_path})")


if __name__ == "__main__":
    main()
