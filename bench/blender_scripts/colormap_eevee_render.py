"""EEVEE part of the colour-map sample-count sweep (issue #12): EEVEE Legacy in
Debian's Blender 3.4, headless under Xvfb with Mesa's llvmpipe. Run by
colormap_benchmark.py:

    xvfb-run -a blender -b --factory-startup --python bench/blender_scripts/colormap_eevee_render.py -- OUT

Scenes, cache (OUT/eevee_results.json, resumable) and environment variables
as bench/blender_scripts/colormap_render.py (whose harness this uses); EEVEE's own:
  PENUMBRA_BENCH_EEVEE_SAMPLES      render samples (taa_render_samples), "1,16,64"
  PENUMBRA_BENCH_EEVEE_REF_SCALE    the reference's supersampling factor K (8)
  PENUMBRA_BENCH_EEVEE_REF_SAMPLES  the reference's samples per large pixel (32)

EEVEE renders the same image every time, so the "seeds" are offsets of the
noise pattern (colormap_scene.offset_noise, the same for the plain ramp,
Penumbra and the reference), each with its own reference.

The reference is the plain ramp rendered K times larger (plus a margin of
ceil(filter_size) pixels on each side, the camera widened to match, so that
border pixels have their whole filter) and scaled down with EEVEE's own pixel
filter. EEVEE Legacy (source/blender/draw/engines/eevee/eevee_temporal_sampling.c,
3.4) jitters sample n by Halton(2, 3) points mapped through the inverse CDF of
filter_blackman_harris (0.35875 − 0.48829 cos x + 0.14128 cos 2x − 0.01168 cos 3x,
x = 2π(u + ½), u ∈ [−½, ½]), scaled to ±2·filter_size and applied with
window_translate_m4 as ofs / viewport size in NDC, i.e. ofs / 2 pixels: each
axis independently, Blackman-Harris over ±filter_size pixels; the samples are
averaged with equal weights. So the expected image is the scene convolved with
that separable filter, and the scale-down uses it: weights BH((x_big − x_pixel)
/ (2r)) per axis, normalized. The large render has its own filter, of radius
filter_size / K output pixels, so r = filter_size·sqrt(1 − 1/K²) keeps the
total variance that of BH(±filter_size) (0.8 % narrower at K = 8).
`filter_check` measures the plain ramp at the most samples against references
scaled down with 0.5…2 times that radius; `first_sample_check` whether the
first sample sits at the pixel centre."""

import math
import os
import sys

# llvmpipe compiles the Penumbra material's shader (16 taps × octaves of noise)
# for tens of minutes with LLVM's optimizer (it spends them in scalar evolution);
# without it, in about 45 s. Read when the first render creates the GL context.
os.environ.setdefault("GALLIVM_PERF", "nopt")
os.environ.setdefault("LP_NUM_THREADS", os.environ.get("PENUMBRA_BENCH_THREADS", "2"))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))  # bench.helpers
from bench.blender_scripts import colormap_render as harness  # noqa: E402
from bench.blender_scripts.colormap_render import colormap_scene  # noqa: E402
from bench.helpers.log import log  # noqa: E402

FILTER_SIZE = 1.5       # render.filter_size (EEVEE) = cycles.filter_width (what the bake reads), both defaults
CHECK_FACTORS = (0.5, 0.75, 1.0, 1.5, 2.0)


def noise_offset(seed):
    """Texture-space offset of the noise for EEVEE's seed `seed` (0: the benchmark scene itself)."""
    return (17.3 * seed, -29.1 * seed, 7.7 * seed)


def blackman_harris(u):
    """EEVEE Legacy's filter_blackman_harris, u ∈ [−½, ½] across its support (0 outside)."""
    x = 2.0 * math.pi * (u + 0.5)
    w = 0.35875 - 0.48829 * np.cos(x) + 0.14128 * np.cos(2 * x) - 0.01168 * np.cos(3 * x)
    return np.where(np.abs(u) <= 0.5, w, 0.0)


def downscale_weights(count, factor, margin, radius):
    """(count, (count + 2·margin)·factor) normalized weights: output pixel i
    (centre i + ½) from the large pixels (centres (a + ½)/factor − margin)."""
    centres = np.arange(count) + 0.5
    large = (np.arange((count + 2 * margin) * factor) + 0.5) / factor - margin
    w = blackman_harris((large[None, :] - centres[:, None]) / (2.0 * radius))
    return w / w.sum(axis=1, keepdims=True)


def downscale(image, size, factor, margin, radius):
    """The large render (rows, columns, channels) filtered down to size = (width, height)."""
    wy = downscale_weights(size[1], factor, margin, radius)
    wx = downscale_weights(size[0], factor, margin, radius)
    rows = (wy @ image.reshape(image.shape[0], -1)).reshape(size[1], image.shape[1], image.shape[2])
    return np.einsum("yXc,xX->yxc", rows, wx).astype(np.float32)


def overscan(scene, margin, factor):
    """Makes the scene render the same view with `margin` more pixels on each
    side, `factor` times larger; returns a function that puts it back."""
    render, cam = scene.render, scene.camera.data
    width, height = render.resolution_x, render.resolution_y
    saved = (width, height, cam.sensor_width, cam.sensor_height, cam.ortho_scale, cam.shift_x, cam.shift_y)
    fitted = width if cam.sensor_fit == "HORIZONTAL" or (cam.sensor_fit == "AUTO" and width >= height) else height
    grow = (fitted + 2 * margin) / fitted
    if cam.type == "ORTHO":
        cam.ortho_scale *= grow
    elif cam.sensor_fit == "VERTICAL":
        cam.sensor_height *= grow
    else:  # HORIZONTAL, or AUTO: sensor_width spans the larger side
        cam.sensor_width *= grow
    cam.shift_x, cam.shift_y = cam.shift_x / grow, cam.shift_y / grow
    render.resolution_x, render.resolution_y = (width + 2 * margin) * factor, (height + 2 * margin) * factor

    def restore():
        (render.resolution_x, render.resolution_y, cam.sensor_width, cam.sensor_height, cam.ortho_scale,
         cam.shift_x, cam.shift_y) = saved
    return restore


class Eevee:
    name = "eevee"

    def __init__(self):
        self.cfg = None

    def configure(self, scene, cfg):
        if bpy.app.version >= (4, 2, 0):
            raise SystemExit("colormap_eevee_render.py measures EEVEE Legacy (Blender 3.x–4.1): its reference "
                             "filter is Legacy's; this is Blender " + bpy.app.version_string)
        self.cfg = cfg
        scene.render.engine = "BLENDER_EEVEE"
        eevee = scene.eevee
        # Emission in a black world: EEVEE's lighting changes nothing here, but at
        # their default sizes its world probe and shadow maps cost ~2 s per render.
        eevee.gi_cubemap_resolution, eevee.gi_visibility_resolution = "64", "8"
        eevee.gi_diffuse_bounces = 0
        eevee.shadow_cube_size, eevee.shadow_cascade_size = "64", "64"
        for flag in ("use_soft_shadows", "use_gtao", "use_bloom", "use_ssr", "use_motion_blur",
                     "use_volumetric_lights"):
            setattr(eevee, flag, False)
        scene.render.filter_size = FILTER_SIZE
        scene.cycles.filter_width = FILTER_SIZE

    def reference_settings(self, cfg):
        cfg = cfg or self.cfg
        return {"scale": cfg["ref_scale"], "samples": cfg["ref_samples"], "margin": math.ceil(FILTER_SIZE),
                "filter_size": FILTER_SIZE, "radius": "filter_size*sqrt(1-1/K^2)"}

    def reference_id(self, seed):
        return f"reference_seed{seed}"

    def reference_count(self, cfg):
        return cfg["seeds"]

    def set_seed(self, ctx, seed):
        colormap_scene.offset_noise(ctx.obj, noise_offset(seed))

    def set_samples(self, scene, samples):
        scene.eevee.taa_render_samples = samples

    def render_large(self, ctx, path, factor, samples):
        """The plain ramp K times larger with the margin; returns (image, wall s, CPU s)."""
        margin = math.ceil(FILTER_SIZE)
        restore = overscan(ctx.scene, margin, factor)
        try:
            self.set_samples(ctx.scene, samples)
            harness.update(ctx.scene)
            seconds, cpu = harness.render(ctx.scene, path)
        finally:
            restore()
        image = harness.read(path)
        os.remove(path)
        return image, seconds, cpu

    def render_reference(self, ctx, path):
        factor, margin = self.cfg["ref_scale"], math.ceil(FILTER_SIZE)
        size = (ctx.scene.render.resolution_x, ctx.scene.render.resolution_y)
        large, seconds, cpu = self.render_large(ctx, path + ".large.exr", factor, self.cfg["ref_samples"])
        radius = FILTER_SIZE * math.sqrt(1.0 - 1.0 / factor ** 2)
        harness.native.require().image.write_exr(path, downscale(large, size, factor, margin, radius), half=False)
        if path.endswith("reference_seed0.exr"):  # for filter_check
            for k in CHECK_FACTORS:
                harness.native.require().image.write_exr(path.replace(".exr", f"_radius{k:g}.exr"),
                                                         downscale(large, size, factor, margin, radius * k),
                                                         half=False)
        return seconds, cpu

    def warm_up(self, ctx, path):
        """One untimed render after switching methods: compiles the material's shader."""
        self.set_samples(ctx.scene, 1)
        harness.update(ctx.scene)
        seconds, _ = harness.render(ctx.scene, path)
        os.remove(path)
        log(f"{ctx.name}: first render (shader compilation) {seconds:.1f} s")
        return seconds

    def probe_plan(self, full):
        return {"plain": (1, 64), "penumbra": (1, 64)}

    def probe_reference(self, ctx, full, path):
        counts, times = (2, 6), []
        for samples in counts:
            _, seconds, cpu = self.render_large(ctx, path, full["ref_scale"], samples)
            times.append((seconds, cpu))
        return {"spp": list(counts), "seconds": [t[0] for t in times], "cpu_seconds": [t[1] for t in times]}

    def reference_seconds(self, fits, full, factor):
        a, b = fits["reference"]
        return a + b * full["ref_samples"] * factor

    def engine_info(self):
        if not harness.RENDERS:  # no GL context yet: asking the gpu module would crash Blender 3.4
            return None
        info = {"GALLIVM_PERF": os.environ.get("GALLIVM_PERF"), "LP_NUM_THREADS": os.environ.get("LP_NUM_THREADS")}
        try:
            import gpu
            info.update(renderer=gpu.platform.renderer_get(), version=gpu.platform.version_get())
        except Exception as error:  # no GPU module or context: only informative
            info["renderer"] = f"unknown ({error})"
        return info

    def extra(self, results, cfg, out):
        results.data["filter_check"] = filter_check(cfg, out)
        results.data["first_sample"] = first_sample_check(self, results, cfg, out)


def filter_check(cfg, out):
    """Per scene: RMSE of the plain ramp at the most samples (seed 0) against
    the reference scaled down with radius × CHECK_FACTORS: the right filter
    should give the smallest error (the rest is the render's own noise)."""
    samples, checks = max(cfg["spp"]), {}
    for name in cfg["scenes"]:
        folder = os.path.join(out, "eevee", name)
        render_path = os.path.join(folder, f"plain_{samples}spp_seed0.exr")
        refs = {k: os.path.join(folder, f"reference_seed0_radius{k:g}.exr") for k in CHECK_FACTORS}
        if os.path.isfile(render_path) and all(os.path.isfile(p) for p in refs.values()):
            image = harness.read(render_path)
            checks[name] = {"samples": samples,
                            "rmse": {f"{k:g}": harness.rmse(image, harness.read(p)) for k, p in refs.items()}}
    return checks


def first_sample_check(runner, results, cfg, out):
    """Max |difference| between 1-sample renders with filter_size 1.5 and
    0.001: zero when EEVEE puts its first sample at the pixel centre."""
    key = bpy.app.version_string
    if results.data.get("first_sample", {}).get("blender") == key:
        return results.data["first_sample"]
    size = harness.scene_size("plane", harness.config("eevee", quick=True, environment=False))
    ctx = harness.build(runner, "plane", size, cfg, os.path.join(out, "first_sample"))
    harness.set_method(ctx, "plain")
    images = []
    for filter_size in (FILTER_SIZE, 0.001):
        ctx.scene.render.filter_size = filter_size
        runner.set_samples(ctx.scene, 1)
        harness.update(ctx.scene)
        path = os.path.join(out, "eevee", "first_sample.exr")
        harness.render(ctx.scene, path)
        images.append(harness.read(path))
        os.remove(path)
    difference = float(np.abs(images[0] - images[1]).max())
    log(f"first sample: max |filter_size {FILTER_SIZE} − 0.001| = {difference:.2e}")
    return {"blender": key, "max_abs_difference": difference, "size": list(size)}


if __name__ == "__main__":
    harness.main(Eevee())
