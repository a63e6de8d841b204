"""Guards issue #12's per-sample verdicts, which bench/colormap_benchmark.py
prints for every scene of its Cycles sweep ("Done when (issue #12)"), on one
small scene: the benchmark plane at 48×27 (the sweep's quick size), seeds 0
and 1, 1, 4, 16 and 64 spp, the plain ramp at 1024 spp as the reference.
Rendered by the sweep's own harness (bench/blender_scripts/colormap_render.py's sweep_scene)
and judged by the sweep's own verdicts (bench/helpers/colormap_criteria.py):
at 1 spp below the plain ramp at 16, at 4 and 16 spp at most 0.8× the plain
ramp, at 64 no worse than it within 2σ. The 256-spp verdict is left out:
those renders alone would take longer than the rest.

Shown able to fail: the same verdicts on the same renders with the plain
ramp in the filter's place (the benchmark's baseline against itself) fail
at 1, 4 and 16 spp, and with the two methods swapped fail at every sample
count. Runs in bpy 4.5 only (conftest.py's ONLY_IN collects it there and
nowhere else), the Blender the benchmark's Cycles sweep runs in."""

import pytest

from bench.blender_scripts import colormap_render as sweep  # the Cycles sweep's harness
from bench.helpers.colormap_criteria import criteria, seed_statistics

SCENE = "plane"
CONFIG = {"scenes": [SCENE], "scale": 0.25, "seeds": 2, "spp": [1, 4, 16, 64], "ref_spp": 1024, "threads": 2}
VERDICTS = ("Penumbra at 1 spp < plain at 16 spp", "4 spp: Penumbra ≤ 0.8 × plain",
            "16 spp: Penumbra ≤ 0.8 × plain", "64 spp: Penumbra no worse than plain within 2σ")
NOT_MEASURED = "256 spp: Penumbra no worse than plain within 2σ"


@pytest.fixture(scope="module")
def renders(tmp_path_factory):
    """The sweep's entries for SCENE: {"scene|method|spp|seed": {"rmse", ...}}."""
    import penumbra
    out = str(tmp_path_factory.mktemp("colormap_sweep"))
    penumbra.register()
    try:
        results = sweep.Results(out, "cycles")
        sweep.sweep_scene(sweep.Cycles(), SCENE, CONFIG, out, results, sweep.addon_fingerprint())
    finally:
        penumbra.unregister()
    return results.data["renders"]


def _relabelled(renders, roles):
    """The renders with each role of the verdicts (plain, penumbra) played by
    the method `roles` names for it."""
    out = {}
    for key, entry in renders.items():
        scene, method, rest = key.split("|", 2)
        for role, source in roles.items():
            if method == source:
                out[f"{scene}|{role}|{rest}"] = entry
    return out


@pytest.mark.parametrize("roles, failing", [
    ({"plain": "plain", "penumbra": "penumbra"}, ()),
    ({"plain": "plain", "penumbra": "plain"}, VERDICTS[:3]),
    ({"plain": "penumbra", "penumbra": "plain"}, VERDICTS),
], ids=["filtered ramp", "plain ramp in its place", "methods swapped"])
def test_filtered_ramp_meets_the_sweeps_per_sample_verdicts(renders, roles, failing):
    data = {"config": CONFIG, "renders": _relabelled(renders, roles)}
    verdicts = {label: (status, values) for status, _, label, values in
                criteria("cycles", seed_statistics(data), CONFIG)}
    assert verdicts.pop(NOT_MEASURED)[0] == "SKIP"
    expected = {label: "FAIL" if label in failing else "PASS" for label in VERDICTS}
    assert {label: status for label, (status, _) in verdicts.items()} == expected, verdicts
