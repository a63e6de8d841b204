"""Sample-count sweep of the colour-map filter (issue #12), Cycles part, and the
harness bench/blender_scripts/colormap_eevee_render.py shares. Run by colormap_benchmark.py:

    .venv/bin/python bench/blender_scripts/colormap_render.py -- OUT           (bpy module)
    blender -b --factory-startup --python bench/blender_scripts/colormap_render.py -- OUT

For every scene in SCENES the plain ColorRamp and Penumbra's filtered ramp are
rendered at each sample count and seed and compared (RMSE over RGB) with a
reference. Cycles on the CPU, no denoising, no adaptive sampling, seeds =
scene.cycles.seed 0..n-1; the reference is the plain ramp at REF spp
(seed 1000, one per scene). The sample count is set on the scene before each
render and the depsgraph updated, so a filter that reads it through a driver
sees it.

Settings (environment; defaults are the full sweep of the issue):
  PENUMBRA_BENCH_QUICK=1    quick: 48×27, spp 1,4,16, reference 256 spp, 2 seeds,
                            scenes plane,torus, plus a timing probe at full size
                            that estimates the full sweep's time
  PENUMBRA_BENCH_SCALE      resolution factor on 192×108 (quick 0.25)
  PENUMBRA_BENCH_SPP        Cycles sample counts, e.g. "1,4,16,64,256"
  PENUMBRA_BENCH_REF_SPP    Cycles reference samples (4096)
  PENUMBRA_BENCH_SEEDS      number of seeds (4)
  PENUMBRA_BENCH_SCENES     comma-separated subset of SCENES
  PENUMBRA_BENCH_EEVEE_SCENES  the EEVEE sweep's own subset (default: as above)
  PENUMBRA_BENCH_THREADS    render threads (2)
  PENUMBRA_BENCH_PROBE      1/0: run the timing probe (default: quick mode only)
  PENUMBRA_BENCH_FILTER_QUALITY  the Noise Filter preset baked (default: the add-on's)

OUT/<renderer>_results.json holds one entry per (scene, method, spp, seed)
with the signature of what it was measured with (Blender, scene, size,
reference, and for Penumbra a hash of the add-on build); an interrupted or
repeated run re-renders only missing or outdated entries. Renders are 32-bit
EXR under OUT/<renderer>/<scene>/; those of seed 0 and the references stay."""

import hashlib
import json
import math
import os
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))  # bench.helpers
from bench.helpers.paths import use_addon  # noqa: E402

use_addon()
import colormap_scene  # noqa: E402
import penumbra  # noqa: E402
from penumbra import native  # noqa: E402
from bench.helpers.log import log  # noqa: E402  (colormap_benchmark.py echoes these lines)

HARNESS_VERSION = 2          # bump when a change here changes what an entry means
BASE_SIZE = (192, 108)
RENDERS = 0                  # renders made by this process
METHODS = ("plain", "penumbra")
SILHOUETTE_MARGIN = 2        # pixels: the pixel filter's reach (1.5) rounded up

# name: (builder in colormap_scene, its keyword arguments, resolution factor, description)
SCENES = {
    "plane": ("noise_ramp_plane", {"roughness": 0.5}, 1,
              "the benchmark plane (Noise Scale 2, Detail 4, Roughness 0.5, two-stop sharp ramp)"),
    "plane_384": ("noise_ramp_plane", {"roughness": 0.5}, 2, "the benchmark plane at twice the resolution"),
    "grazing": ("noise_ramp_plane", {"roughness": 0.5, "camera_location": (0.0, -2.0, 0.6),
                                     "camera_rotation_degrees": (87.5, 0.0, 0.0)}, 1,
                "the plane seen from 0.6 above it, pitched 87.5° (the horizon near the middle)"),
    "constant": ("noise_ramp_plane", {"roughness": 0.5, "interpolation": "CONSTANT",
                                      "stops": colormap_scene.CONSTANT_STOPS}, 1,
                 "the plane, a four-stop Constant ramp"),
    "hsv_8_stops": ("noise_ramp_plane", {"roughness": 0.5, "color_mode": "HSV",
                                         "stops": colormap_scene.HSV_STOPS}, 1,
                    "the plane, an eight-stop ramp around the hue circle in HSV colour mode"),
    "detail_8_distortion": ("noise_ramp_plane", {"roughness": 0.5, "detail": 8.0, "distortion": 0.5}, 1,
                            "the plane, noise Detail 8 and Distortion 0.5"),
    "torus": ("noise_ramp_torus", {"roughness": 0.5}, 1,
              "a smooth torus (Noise Scale 10), seen from 35° above: head-on to grazing at its silhouettes and hole"),
}

FULL = {"scale": 1.0, "seeds": 4, "scenes": list(SCENES),
        "cycles": {"spp": [1, 4, 16, 64, 256], "ref_spp": 4096},
        "eevee": {"spp": [1, 16, 64], "ref_scale": 8, "ref_samples": 32}}
QUICK = {"scale": 0.25, "seeds": 2, "scenes": ["plane", "torus"],
         "cycles": {"spp": [1, 4, 16], "ref_spp": 256},
         "eevee": {"spp": [1, 16], "ref_scale": 4, "ref_samples": 16}}


def _ints(text):
    return [int(v) for v in text.replace(" ", "").split(",") if v]


def config(renderer, quick=None, environment=True):
    """The sweep's settings: FULL or QUICK, overridden by the environment."""
    env = os.environ if environment else {}
    if quick is None:
        quick = env.get("PENUMBRA_BENCH_QUICK", "0") not in ("", "0")
    base = QUICK if quick else FULL
    cfg = {"renderer": renderer, "quick": quick, "scale": float(env.get("PENUMBRA_BENCH_SCALE", base["scale"])),
           "seeds": int(env.get("PENUMBRA_BENCH_SEEDS", base["seeds"])),
           "scenes": [s for s in env.get(("PENUMBRA_BENCH_EEVEE_SCENES" if renderer == "eevee" and
                                           "PENUMBRA_BENCH_EEVEE_SCENES" in env else "PENUMBRA_BENCH_SCENES"),
                                          ",".join(base["scenes"])).split(",") if s],
           "threads": int(env.get("PENUMBRA_BENCH_THREADS", "2")),
           "probe": env.get("PENUMBRA_BENCH_PROBE", "1" if quick else "0") not in ("", "0"),
           "filter_quality": env.get("PENUMBRA_BENCH_FILTER_QUALITY") or None}
    cfg.update(base[renderer])
    prefix = "PENUMBRA_BENCH_" if renderer == "cycles" else "PENUMBRA_BENCH_EEVEE_"
    if prefix + ("SPP" if renderer == "cycles" else "SAMPLES") in env:
        cfg["spp"] = _ints(env[prefix + ("SPP" if renderer == "cycles" else "SAMPLES")])
    for key in ("ref_spp", "ref_scale", "ref_samples"):
        if key in cfg and prefix + key.upper() in env:
            cfg[key] = int(env[prefix + key.upper()])
    unknown = [s for s in cfg["scenes"] if s not in SCENES]
    if unknown:
        raise SystemExit(f"unknown scene(s) {unknown}; known: {', '.join(SCENES)}")
    return cfg


def scene_size(name, cfg):
    factor = SCENES[name][2] * cfg["scale"]
    return max(4, round(BASE_SIZE[0] * factor)), max(4, round(BASE_SIZE[1] * factor))


def octaves(name):
    return math.floor(SCENES[name][1].get("detail", 4.0)) + 1


def _hash(*parts):
    h = hashlib.sha1()
    for part in parts:
        h.update(json.dumps(part, sort_keys=True, default=str).encode())
    return h.hexdigest()[:16]


def _file_hash(paths):
    h = hashlib.sha1()
    for path in sorted(paths):
        h.update(os.path.basename(path).encode())
        with open(path, "rb") as f:
            h.update(f.read())
    return h.hexdigest()[:16]


def addon_fingerprint():
    """Hash of the add-on build this process imported: the colour-map tool's
    files and the compiled core (a Penumbra entry is outdated when it changes)."""
    here = os.path.dirname(os.path.abspath(penumbra.__file__))
    folder = os.path.join(here, "colormap")
    files = [os.path.join(folder, f) for f in os.listdir(folder) if f.endswith((".py", ".json"))]
    core = native.require()
    return _file_hash(files + [core.__file__])


class Results:
    """OUT/<renderer>_results.json, written after every render."""

    def __init__(self, out, renderer):
        self.path = os.path.join(out, f"{renderer}_results.json")
        self.data = {"renders": {}, "references": {}}
        if os.path.isfile(self.path):
            with open(self.path) as f:
                self.data = json.load(f)

    def get(self, table, key, signature):
        entry = self.data[table].get(key)
        return entry if entry is not None and entry.get("signature") == signature else None

    def put(self, table, key, entry):
        self.data[table][key] = entry
        self.save()

    def save(self):
        with open(self.path + ".tmp", "w") as f:
            json.dump(self.data, f, indent=1)
        os.replace(self.path + ".tmp", self.path)


def render_key(name, method, spp, seed):
    return f"{name}|{method}|{spp}|{seed}"


# ---- the scene ------------------------------------------------------------

def new_scene(size, threads):
    """Factory settings, the size, 32-bit EXR output, Standard view, black world."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"
    scene.render.threads_mode = "FIXED"
    scene.render.threads = threads
    world = bpy.data.worlds.new("black")
    if bpy.app.version < (5, 0, 0):
        world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.world = world
    return scene


class Context:
    """One built and baked scene: its Blender objects and the time it took."""

    def __init__(self, name, scene, built, seconds):
        self.name, self.scene = name, scene
        self.obj, self.material, self.ramp, self.emission, self.camera = built
        self.build_seconds = seconds


def build(runner, name, size, cfg, out, bake=True):
    """New scene with the runner's engine, the variant `name`, baked (or not)."""
    started = time.perf_counter()
    scene = new_scene(size, cfg["threads"])
    runner.configure(scene, cfg)
    builder, kwargs, _, _ = SCENES[name]
    built = getattr(colormap_scene, builder)(**kwargs)
    if not bake:
        return Context(name, scene, built, time.perf_counter() - started)
    if cfg.get("filter_quality"):
        scene.penumbra.colormap.filter_quality = cfg["filter_quality"]
    scene.penumbra.colormap.output_folder = os.path.join(out, runner.name, name, "lookup")
    result = bpy.ops.penumbra.bake_colormap_lut()
    if result != {"FINISHED"}:
        raise RuntimeError(f"bake failed in scene {name}: {result}")
    tree = built[1].node_tree
    for node_name in ("Penumbra Filtered Ramp", "Penumbra Noise Filter"):
        if node_name not in tree.nodes:
            raise RuntimeError(f"the bake left no '{node_name}' node in scene {name}")
    return Context(name, scene, built, time.perf_counter() - started)


def set_method(ctx, method):
    """plain: the original ramp on the noise; penumbra: the filtered ramp."""
    tree = ctx.material.node_tree
    group = tree.nodes["Penumbra Filtered Ramp"]
    ctx.ramp.mute = method == "penumbra"
    if method == "penumbra":
        tree.links.new(group.outputs["Color"], ctx.emission.inputs["Color"])
    else:
        noise = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeTexNoise")
        tree.links.new(ctx.ramp.outputs["Color"], ctx.emission.inputs["Color"])
        tree.links.new(noise.outputs["Fac"], ctx.ramp.inputs["Fac"])


def update(scene):
    """Lets drivers (e.g. one reading the sample count) and the depsgraph catch up."""
    bpy.context.view_layer.update()
    scene.frame_set(scene.frame_current)


def driven_values(material):
    """Every driver on the material's tree and the node groups, with its value now."""
    out = {}
    for tree in [material.node_tree] + list(bpy.data.node_groups):
        anim = tree.animation_data
        for fcurve in (anim.drivers if anim else ()):
            try:
                value = tree.path_resolve(fcurve.data_path)
                value = float(value[fcurve.array_index] if hasattr(value, "__len__") else value)
            except (ValueError, TypeError, IndexError):
                value = None
            label = f"{tree.name}: {fcurve.data_path}"
            out[label if fcurve.driver.is_valid else label + " (invalid driver)"] = value
    return out


def render(scene, path):
    """Renders to `path`; returns (wall-clock seconds, CPU seconds of this
    process, all threads: unlike the wall clock, not inflated when other jobs
    share the machine)."""
    global RENDERS
    scene.render.filepath = path
    started, cpu = time.perf_counter(), time.process_time()
    bpy.ops.render.render(write_still=True)
    RENDERS += 1
    if not os.path.isfile(path):
        raise RuntimeError(f"the render wrote no {path}")
    return time.perf_counter() - started, time.process_time() - cpu


def read(path):
    return native.require().image.read(path)


def rmse(image, reference, mask=None):
    squared = (image - reference) ** 2
    return float((squared.mean() if mask is None else squared[mask].mean()) ** 0.5)


def interior_mask(reference, margin=SILHOUETTE_MARGIN):
    """Pixels at least `margin` pixels from any pixel the reference shows the
    (black) background in. Silhouettes alias at low sample counts whatever
    the texture does; the error away from them is the texture filter's own."""
    covered = reference.sum(axis=2) > 1e-6     # no ramp stop is black; the world is
    padded = np.pad(covered, margin, constant_values=True)
    interior = np.ones_like(covered)
    for dy in range(2 * margin + 1):
        for dx in range(2 * margin + 1):
            interior &= padded[dy:dy + covered.shape[0], dx:dx + covered.shape[1]]
    return interior


# ---- the sweep ------------------------------------------------------------

def signatures(runner, name, size, cfg, addon):
    """What an entry was measured with: plain renders and references depend on
    the scene, its size, Blender and the reference's settings; Penumbra's also
    on the add-on build."""
    base = _hash(HARNESS_VERSION, bpy.app.version_string, runner.name, SCENES[name][:2], size,
                 _file_hash([colormap_scene.__file__]), runner.reference_settings(cfg))
    quality = cfg.get("filter_quality")      # the add-on's default keeps the signatures of before
    return {"reference": base, "plain": base, "penumbra": _hash(base, addon, quality) if quality else _hash(base, addon)}


def reference(runner, ctx, seed, signature, folder, results):
    """The reference image for `seed` (rendered, or read back when cached)."""
    ref_id = runner.reference_id(seed)
    key, path = f"{ctx.name}|{ref_id}", os.path.join(folder, ref_id + ".exr")
    if results.get("references", key, signature) is None or not os.path.isfile(path):
        set_method(ctx, "plain")
        runner.set_seed(ctx, seed)
        seconds, cpu = runner.render_reference(ctx, path)
        results.put("references", key, {"signature": signature, "seconds": seconds, "cpu_seconds": cpu,
                                        "path": path, "settings": runner.reference_settings(None)})
        log(f"{ctx.name}: reference {ref_id} in {seconds:.1f} s")
    return read(path)


def sweep_scene(runner, name, cfg, out, results, addon):
    size = scene_size(name, cfg)
    sig = signatures(runner, name, size, cfg, addon)
    seeds = list(range(cfg["seeds"]))
    todo = [(m, spp, seed) for m in METHODS for seed in seeds for spp in cfg["spp"]
            if results.get("renders", render_key(name, m, spp, seed), sig[m]) is None]
    if not todo:
        log(f"{name}: all renders cached")
        return
    ctx = build(runner, name, size, cfg, out)
    folder = os.path.join(out, runner.name, name)
    references, interiors = {}, {}
    for seed in seeds:
        ref_id = runner.reference_id(seed)
        if ref_id not in references:
            references[ref_id] = reference(runner, ctx, seed, sig["reference"], folder, results)
            interiors[ref_id] = interior_mask(references[ref_id])
    for method in METHODS:
        pending = sorted((seed, spp) for m, spp, seed in todo if m == method)
        if not pending:
            continue
        set_method(ctx, method)
        warm_up = runner.warm_up(ctx, os.path.join(folder, "warm_up.exr"))
        for seed, spp in pending:
            runner.set_seed(ctx, seed)
            runner.set_samples(ctx.scene, spp)
            update(ctx.scene)
            path = os.path.join(folder, f"{method}_{spp}spp_seed{seed}.exr")
            seconds, cpu = render(ctx.scene, path)
            image, ref_id = read(path), runner.reference_id(seed)
            error = rmse(image, references[ref_id])
            interior = rmse(image, references[ref_id], interiors[ref_id]) if interiors[ref_id].any() else None
            if seed != 0:  # seed 0 stays for the pictures
                os.remove(path)
            results.put("renders", render_key(name, method, spp, seed), {
                "scene": name, "method": method, "spp": spp, "seed": seed, "rmse": error, "rmse_interior": interior,
                "interior_fraction": float(interiors[ref_id].mean()), "seconds": seconds,
                "cpu_seconds": cpu, "size": list(size), "signature": sig[method], "warm_up_seconds": warm_up,
                "load_average": os.getloadavg()[0],
                "driven": driven_values(ctx.material)})
            log(f"{name:20s} {method:8s} {spp:4d} spp seed {seed}: RMSE {error:.5f}  {seconds:.2f} s")


# ---- estimating the full sweep from a timing probe ------------------------

def probe(runner, out, results):
    """Renders the benchmark plane at the full sweep's size at a few sample
    counts (after one untimed render: compilation) for each method, and the
    reference's cost: what `estimate_full` extrapolates from."""
    full = config(runner.name, quick=False, environment=False)
    size = scene_size("plane", full)
    plan = runner.probe_plan(full)
    signature = _hash(HARNESS_VERSION, bpy.app.version_string, runner.name, size, addon_fingerprint(), plan)
    if results.data.get("probe", {}).get("signature") == signature:
        return results.data["probe"]
    ctx = build(runner, "plane", size, full, os.path.join(out, "probe"))
    record = {"signature": signature, "size": list(size), "build_seconds": ctx.build_seconds}
    path = os.path.join(out, runner.name, "probe.exr")
    for method, counts in plan.items():
        set_method(ctx, method)
        times = []
        for spp in (counts[0],) + tuple(counts):
            runner.set_samples(ctx.scene, spp)
            update(ctx.scene)
            times.append(render(ctx.scene, path))
        record[method] = {"spp": list(counts), "seconds": [t[0] for t in times[1:]],
                          "cpu_seconds": [t[1] for t in times[1:]], "first_seconds": times[0][0],
                          "first_cpu_seconds": times[0][1]}
        log(f"probe {method}: {counts} spp at {size[0]}×{size[1]}: " +
            ", ".join(f"{w:.2f} s (CPU {c:.2f} s)" for w, c in times[1:]) + f"; first render {times[0][0]:.1f} s")
    set_method(ctx, "plain")
    record["reference"] = runner.probe_reference(ctx, full, path)
    results.data["probe"] = record
    results.save()
    return record


def line(counts, seconds):
    """Least-squares t = a + b·n."""
    n = len(counts)
    mx, my = sum(counts) / n, sum(seconds) / n
    sxx = sum((x - mx) ** 2 for x in counts)
    b = sum((x - mx) * (y - my) for x, y in zip(counts, seconds)) / sxx if sxx else 0.0
    return my - b * mx, max(b, 0.0)


def _fit(entry, idle, threads):
    """(a, b) of t = a + b·n for a probe entry. idle: what an otherwise idle
    machine would take: the per-sample part from CPU time / threads, the
    fixed part the smaller of wall and CPU time (it is mostly one thread)."""
    if not idle:
        return line(entry["spp"], entry["seconds"])
    a_wall, _ = line(entry["spp"], entry["seconds"])
    a_cpu, b_cpu = line(entry["spp"], entry["cpu_seconds"])
    return min(a_wall, a_cpu), b_cpu / threads


def estimate_full(runner, record, idle=False, compile_seconds=0.0):
    """Seconds per scene of the full sweep: each render a + b·n (fitted per
    method on the probe), b scaled by the scene's pixel count and, for
    Penumbra, its number of noise octaves; plus the scene's build and bake,
    each method's first-render overhead, and `compile_seconds` (the longest
    first render of the sweep: EEVEE compiling Penumbra's shader) once per
    octave count (scenes with the same count reuse the compiled shader)."""
    full = config(runner.name, quick=False, environment=False)
    pixels = record["size"][0] * record["size"][1]
    fits = {k: _fit(record[k], idle, full["threads"]) for k in METHODS + ("reference",) if record.get(k)}
    first_key, key = ("first_cpu_seconds", "cpu_seconds") if idle else ("first_seconds", "seconds")
    first = sum(max(0.0, record[m][first_key] - record[m][key][0]) for m in METHODS)
    out = {}
    for name in full["scenes"]:
        size = scene_size(name, full)
        factor = size[0] * size[1] / pixels
        seconds = record["build_seconds"] + first
        seconds += runner.reference_seconds(fits, full, factor) * runner.reference_count(full)
        for method in METHODS:
            a, b = fits[method]
            cost = octaves(name) / octaves("plane") if method == "penumbra" else 1.0
            seconds += full["seeds"] * sum(a + b * n * factor * cost for n in full["spp"])
        out[name] = seconds
    if compile_seconds:
        out["shader compilation"] = compile_seconds * len({octaves(n) for n in full["scenes"]})
    return out


def main(runner):
    out = os.path.abspath(sys.argv[sys.argv.index("--") + 1])
    cfg = config(runner.name)
    os.makedirs(out, exist_ok=True)
    penumbra.register()
    results = Results(out, runner.name)
    addon = addon_fingerprint()
    started = time.perf_counter()
    log(f"{runner.name}: scenes {cfg['scenes']}, scale {cfg['scale']}, samples {cfg['spp']}, "
        f"{cfg['seeds']} seeds, reference {runner.reference_settings(cfg)}, {cfg['threads']} threads")
    for name in cfg["scenes"]:
        sweep_scene(runner, name, cfg, out, results, addon)
    results.data.update({"renderer": runner.name, "blender": bpy.app.version_string, "config": cfg,
                         "addon": addon, "sweep_seconds": time.perf_counter() - started,
                         "engine_info": runner.engine_info() or results.data.get("engine_info"),
                         "scenes": {n: {"size": list(scene_size(n, cfg)), "description": SCENES[n][3]}
                                    for n in cfg["scenes"]}})
    runner.extra(results, cfg, out)
    if cfg["probe"]:
        record = probe(runner, out, results)
        compile_seconds = max([r.get("warm_up_seconds") or 0.0 for r in results.data["renders"].values()] + [0.0])
        estimate = {}
        for label, idle in (("measured load", False), ("idle machine", True)):
            per_scene = estimate_full(runner, record, idle, compile_seconds)
            estimate[label] = {"total": sum(per_scene.values()), "scenes": per_scene}
            log(f"{runner.name}: estimated full sweep ({label}) {sum(per_scene.values()) / 60:.1f} min (" +
                ", ".join(f"{n} {s / 60:.1f}" for n, s in per_scene.items()) + ")")
        results.data["estimate_full_seconds"] = estimate
    results.save()
    log(f"{runner.name}: done in {time.perf_counter() - started:.0f} s")
    penumbra.unregister()


# ---- Cycles ---------------------------------------------------------------

class Cycles:
    name = "cycles"
    REFERENCE_SEED = 1000  # apart from the measured seeds 0..n-1

    def __init__(self):
        self.cfg = None

    def configure(self, scene, cfg):
        self.cfg = cfg
        scene.render.engine = "CYCLES"
        scene.cycles.device = "CPU"
        scene.cycles.use_denoising = False
        scene.cycles.use_adaptive_sampling = False
        scene.cycles.use_animated_seed = False

    def reference_settings(self, cfg):
        return {"spp": (cfg or self.cfg)["ref_spp"], "seed": self.REFERENCE_SEED}

    def reference_id(self, seed):
        return "reference"  # one per scene, every seed is compared with it

    def reference_count(self, cfg):
        return 1

    def set_seed(self, ctx, seed):
        ctx.scene.cycles.seed = seed

    def set_samples(self, scene, spp):
        scene.cycles.samples = spp

    def render_reference(self, ctx, path):
        ctx.scene.cycles.seed = self.REFERENCE_SEED
        self.set_samples(ctx.scene, self.cfg["ref_spp"])
        update(ctx.scene)
        return render(ctx.scene, path)

    def warm_up(self, ctx, path):
        return None  # Cycles compiles its shaders in a fraction of a second, inside each render

    def probe_plan(self, full):
        return {"plain": (1, 256), "penumbra": (1, 32)}

    def probe_reference(self, ctx, full, path):
        return None  # the plain ramp's line, extrapolated

    def reference_seconds(self, fits, full, factor):
        a, b = fits["plain"]
        return a + b * full["ref_spp"] * factor

    def engine_info(self):
        return {"device": "CPU", "denoising": False, "adaptive_sampling": False}

    def extra(self, results, cfg, out):
        results.data["texture_bound"] = texture_bound(self, results, cfg, out)


COVERAGE_SPP = 1024


def texture_bound(runner, results, cfg, out):
    """Per scene: the lowest RMSE any texture filter can reach at 1 spp. At
    one sample Cycles shades the pixel's centre only: a pixel whose centre
    ray misses the surface is black whatever the material does, and one
    whose centre hits the surface shows the surface's colour, at best the
    reference's over the pixel's coverage (the surface's filter-weighted
    share of the pixel, rendered as a white emission at COVERAGE_SPP spp).
    That image against the reference: the geometry's own aliasing."""
    bounds = {}
    for name in cfg["scenes"]:
        folder = os.path.join(out, runner.name, name)
        hit_path = os.path.join(folder, "penumbra_1spp_seed0.exr")
        ref_path = os.path.join(folder, "reference.exr")
        if 1 not in cfg["spp"] or not (os.path.isfile(hit_path) and os.path.isfile(ref_path)):
            continue
        size = scene_size(name, cfg)
        signature = _hash(HARNESS_VERSION, bpy.app.version_string, SCENES[name][:2], size, COVERAGE_SPP,
                          _file_hash([colormap_scene.__file__]))
        path = os.path.join(folder, "coverage.exr")
        if results.get("references", f"{name}|coverage", signature) is None or not os.path.isfile(path):
            ctx = build(runner, name, size, cfg, out, bake=False)
            tree = ctx.material.node_tree
            for link in list(ctx.emission.inputs["Color"].links):
                tree.links.remove(link)
            ctx.emission.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
            ctx.scene.cycles.seed = runner.REFERENCE_SEED
            runner.set_samples(ctx.scene, COVERAGE_SPP)
            update(ctx.scene)
            seconds, cpu = render(ctx.scene, path)
            results.put("references", f"{name}|coverage", {"signature": signature, "seconds": seconds,
                                                           "cpu_seconds": cpu, "path": path})
        reference, coverage = read(ref_path), read(path)[..., :1]
        hit = read(hit_path).sum(axis=2, keepdims=True) > 0
        best = np.where(hit, reference / np.maximum(coverage, 1e-6), 0.0)
        interior = interior_mask(reference)
        bounds[name] = {"rmse": rmse(best, reference), "rmse_interior": rmse(best, reference, interior),
                        "missed_covered_pixels": int(((~hit[..., 0]) & (reference.sum(axis=2) > 1e-6)).sum())}
        log(f"{name}: best texture at 1 spp: RMSE {bounds[name]['rmse']:.5f} "
            f"(away from silhouettes {bounds[name]['rmse_interior']:.5f})")
    return bounds


if __name__ == "__main__":
    main(Cycles())
