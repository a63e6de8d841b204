"""EEVEE Next's shadow pool and the light rig (issue #26; docs/lights.md,
"EEVEE Next's shadow pool"). Per scene of the EEVEE benchmark, the default
rig for EEVEE of 32 and 64 suns rendered as the benchmark does (factory
pool, 512 MB), the 64-sun rig again with a 1024 MB pool and with shadows on
its 32 strongest suns only. For each render: the pages EEVEE asked of the
pool when it overflowed (its message "Shadow buffer full ... (needed /
held)", read from the process's output; 0 when it did not), and the mean
and error against Cycles' direct light and against the issue's reference
(both cached by bench/lights_eevee_direct_benchmark.py and the EEVEE
benchmark: run those first). Then one scene's 32-sun rig at 960x720 and 1
sample, to show the pages follow the view, not its pixels. Prints
"RESULT {json}":

    .venv313/bin/python bench/blender_scripts/lights_eevee_shadow_pool.py OUT CACHE MAP
    .venv/bin/python bench/blender_scripts/lights_eevee_shadow_pool.py OUT CACHE MAP"""

import contextlib
import os
import re
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))  # bench.helpers
from bench.blender_scripts.lights_eevee_direct import against, scene_and_references  # noqa: E402
from bench.blender_scripts.lights_eevee_render import Renderer, build_rig, start_blender  # noqa: E402
from bench.helpers.blender_result import report  # noqa: E402
from bench.helpers.lights_eevee import bundled_map, eevee_engine, light_by_map  # noqa: E402
from bench.helpers.lights_render_scene import sunrise_sphere_scene  # noqa: E402
from bench.lights_eevee_benchmark import HEIGHT, REFERENCE_SPP, SCENES, WIDTH  # noqa: E402

OVERFLOW = re.compile(r"Shadow buffer full.*?\((\d+) / (\d+)\)")


@contextlib.contextmanager
def captured_output(sink):
    """The process's stdout and stderr (EEVEE prints from C) into `sink`, a list of one str."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    with tempfile.TemporaryFile() as f:
        os.dup2(f.fileno(), 1)
        os.dup2(f.fileno(), 2)
        try:
            yield
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)
            f.seek(0)
            sink.append(f.read().decode(errors="replace"))


def render_counting_pages(render, stem):
    """(luminance, seconds, pages needed when the pool overflowed, pages it holds)."""
    text = []
    with captured_output(text):
        luma, seconds = render(eevee_engine(), stem)
    found = [(int(a), int(b)) for a, b in OVERFLOW.findall(text[0])]
    return luma, seconds, max((a for a, _ in found), default=0), max((b for _, b in found), default=0)


def measure(render, stem, direct, bounced):
    luma, seconds, needed, held = render_counting_pages(render, stem)
    (error, mean), (issue_error, issue_mean) = against(luma, direct), against(luma, bounced)
    row = {"pages_needed": needed, "pages_held": held, "error": error, "mean": mean,
           "issue_error": issue_error, "issue_mean": issue_mean, "seconds": seconds}
    print(stem, row, flush=True)
    return row


def measure_scene(name, map_path, out, cache, core):
    strength, render, bounced, direct, _ = scene_and_references(name, map_path, cache, core)
    scene = render.scene
    rows = {}
    for count in (32, 64):
        build_rig(strength, out, count)
        rows[f"rig_{count}"] = measure(render, os.path.join(out, f"{name}_{count}"), direct, bounced)
    scene.eevee.shadow_pool_size = "1024"
    rows["rig_64_pool_1024"] = measure(render, os.path.join(out, f"{name}_64_pool"), direct, bounced)
    scene.eevee.shadow_pool_size = "512"
    suns = sorted((o for o in scene.objects if o.type == "LIGHT"), key=lambda o: o.data.energy, reverse=True)
    for sun in suns[32:]:
        sun.data.use_shadow = False
    rows["rig_64_strongest_32"] = measure(render, os.path.join(out, f"{name}_64_strongest"), direct, bounced)
    return rows


def pages_at_full_size(map_path, out, core):
    """Pages of the 32- and 64-sun rigs at ten times the size, 1 sample."""
    scene, strength = sunrise_sphere_scene(REFERENCE_SPP, 1)
    light_by_map(scene, map_path)
    scene.render.resolution_x, scene.render.resolution_y = 10 * WIDTH, 10 * HEIGHT
    render = Renderer(scene, core)
    pages = {}
    for count in (32, 64):
        build_rig(strength, out, count)
        pages[f"rig_{count}"] = render_counting_pages(render, os.path.join(out, f"full_{count}"))[2]
    return pages


def main(result, out, cache, opposite):
    core = start_blender()
    os.makedirs(out, exist_ok=True)
    result.update(scenes={}, load=[os.getloadavg()[0]])
    for name in SCENES:
        map_path = opposite if name == "opposite" else bundled_map(name)
        result["scenes"][name] = measure_scene(name, map_path, out, cache, core)
        result["load"].append(os.getloadavg()[0])
    result["full_size"] = {"size": [10 * WIDTH, 10 * HEIGHT], "scene": "opposite",
                           "pages_needed": pages_at_full_size(opposite, out, core)}


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1 if "--" in sys.argv else 1:][:3]
    report(lambda result: main(result, *args))
