"""Issue #12's verdicts on the colour-map sweep: per sample count, Penumbra's
filtered ramp against the plain ramp, as RMSE against a reference averaged
over seeds. Shared by bench/colormap_benchmark.py (every scene of the sweep)
and tests/blender/colormap/test_colormap_criteria.py (one small scene).

`data` is a sweep's results (bench/blender_scripts/colormap_render.py writes them):
{"config": {"scenes", "spp", "seeds"}, "renders": {"scene|method|spp|seed":
{"rmse", "seconds", ...}}}."""

import math

import numpy as np


def seed_statistics(data, key="rmse"):
    """{scene: {method: {n: dict(mean, std, seeds, seconds, cpu)}}} over the
    seeds of the run's config of the error `key` (rmse: every pixel;
    rmse_interior: pixels away from silhouettes); std is the sample standard
    deviation (n − 1)."""
    cfg, stats = data["config"], {}
    for name in cfg["scenes"]:
        for method in ("plain", "penumbra"):
            for n in cfg["spp"]:
                runs = [data["renders"].get(f"{name}|{method}|{n}|{seed}") for seed in range(cfg["seeds"])]
                if any(r is None or r.get(key) is None for r in runs):
                    continue
                errors = np.array([r[key] for r in runs])
                stats.setdefault(name, {}).setdefault(method, {})[n] = {
                    "mean": float(errors.mean()), "std": float(errors.std(ddof=1)) if len(errors) > 1 else 0.0,
                    "seeds": len(errors), "seconds": float(np.mean([r["seconds"] for r in runs])),
                    "cpu": float(np.mean([r.get("cpu_seconds", r["seconds"]) for r in runs]))}
    return stats


def no_worse(pen, plain):
    """Penumbra no worse than plain within 2σ: mean_pen − mean_plain ≤
    2·sqrt(σ_pen² + σ_plain²)/sqrt(n) (two standard errors of the difference)."""
    bound = 2.0 * math.sqrt(pen["std"] ** 2 + plain["std"] ** 2) / math.sqrt(pen["seeds"])
    delta = pen["mean"] - plain["mean"]
    return delta <= bound, (f"Δ = {delta:+.5f}, 2σ bound {bound:.5f} "
                            f"(Penumbra {pen['mean']:.5f}, plain {plain['mean']:.5f})")


def criteria(renderer, stats, cfg):
    """[(PASS/FAIL/SKIP, scene, criterion, values)]: issue #12's "Done when" per scene."""
    if renderer == "cycles":
        tests = [("Penumbra at 1 spp < plain at 16 spp", ("penumbra", 1), ("plain", 16),
                  lambda p, q: (p["mean"] < q["mean"], f"{p['mean']:.5f} vs {q['mean']:.5f}"))]
        tests += [(f"{n} spp: Penumbra ≤ 0.8 × plain", ("penumbra", n), ("plain", n),
                   lambda p, q: (p["mean"] <= 0.8 * q["mean"], f"{p['mean']:.5f} vs 0.8 × {q['mean']:.5f}"))
                  for n in (4, 16)]
        tests += [(f"{n} spp: Penumbra no worse than plain within 2σ", ("penumbra", n), ("plain", n), no_worse)
                  for n in (64, 256)]
    else:
        tests = [("1 sample: Penumbra ≤ 0.5 × plain", ("penumbra", 1), ("plain", 1),
                  lambda p, q: (p["mean"] <= 0.5 * q["mean"], f"{p['mean']:.5f} vs 0.5 × {q['mean']:.5f}"))]
        tests += [(f"{n} samples: Penumbra no worse than plain within 2σ", ("penumbra", n), ("plain", n), no_worse)
                  for n in (16, 64)]
    out = []
    for name in cfg["scenes"]:
        for label, (ma, na), (mb, nb), test in tests:
            a, b = stats.get(name, {}).get(ma, {}).get(na), stats.get(name, {}).get(mb, {}).get(nb)
            if a is None or b is None:
                out.append(("SKIP", name, label, "not measured in this run"))
                continue
            ok, values = test(a, b)
            out.append(("PASS" if ok else "FAIL", name, label, values))
    return out
