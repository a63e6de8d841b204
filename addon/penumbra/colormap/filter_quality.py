"""The Noise Filter's quality presets (the trade of cost against error the
user picks in the panel) and the table of what each costs and gains, which
bench/colormap_benchmark.py measures and writes to filter_quality.json
beside this file (as it does noise_statistics.json). Free of bpy."""

import collections
import json
import os

# native: the one evaluation is the user's Noise Texture with its Detail cut
# at the sample's resolution (native_filter.py), where the noise allows it;
# taps_at_one: a one-tap preset keeps the 16 taps for one sample.
Quality = collections.namedtuple("Quality", "label taps analytic_octaves mixture description native taps_at_one",
                                 defaults=(False, True))

# Presets: taps per sample, the finest octaves carried only as variance,
# and whether the ramp reads a mixture of four Gaussians or one.
QUALITIES = collections.OrderedDict([
    ("NATIVE", Quality("1 Noise", 1, 0, False,
                       "One Noise Texture with its Detail cut at the sample's resolution, the octaves left out "
                       "carried as variance; one lookup; the 16 taps kept for one sample (other noises: as 1 Eval)",
                       native=True)),
    ("NATIVE_ONLY", Quality("1 Noise Only", 1, 0, False,
                            "As 1 Noise at one sample too: cheapest there, about 2.5× the 16 taps' error at one "
                            "sample", native=True, taps_at_one=False)),
    ("POINT", Quality("1 Eval", 1, 0, False,
                      "Each octave once at the sample, the ones finer than the footprint faded out and carried "
                      "as variance; one lookup")),
    ("POINT_COARSE", Quality("1 Eval Coarse", 1, 1, False,
                             "As 1 Eval, the finest octave never evaluated (its variance carried): "
                             "cheaper, blurrier close up")),
    ("TAPS_4", Quality("4 Taps", 4, 0, False, "Octaves at 4 taps over the kernel, one Gaussian, one lookup")),
    ("TAPS_16_MIXTURE", Quality("16 Taps Mix", 16, 0, True,
                                "Octaves at 16 taps over the kernel, a mixture of four Gaussians, four lookups "
                                "(the filter of Penumbra 0.x before the presets; files baked then use it)")),
])
# The lowest mean equal-time RMSE ratio at 16 spp among the presets that
# converge to the plain ramp and keep the 16 taps for one sample (the
# per-sample verdict at one sample of issue #12; filter_quality.json;
# docs/colormap-benchmark.md, "Equal time"). POINT_COARSE never evaluates
# the finest octave, so it stays blurred where that is resolved;
# NATIVE_ONLY renders the same groups above one sample.
DEFAULT = "NATIVE"
# What a Noise Filter node baked before the presets (no penumbra_quality) is.
LEGACY = "TAPS_16_MIXTURE"
NODE_PROPERTY = "penumbra_quality"
TABLE_PATH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "filter_quality.json")


def quality(key):
    return QUALITIES[key]


def enum_items():
    return [(key, q.label, q.description) for key, q in QUALITIES.items()]


def baked_quality(filter_node):
    """The preset a Noise Filter node was baked with (LEGACY for one baked
    before the presets)."""
    return filter_node.get(NODE_PROPERTY, LEGACY)


def rebake_reason(filter_nodes, chosen):
    """What the panel says when a material's Noise Filters were baked at
    another preset than `chosen` (a material from before the presets counts
    as LEGACY: it keeps rendering with its old groups until baked again):
    "Baked at <label>", or None."""
    baked = [baked_quality(n) for n in filter_nodes]
    if not any(key != chosen for key in baked):
        return None
    return f"Baked at {QUALITIES.get(baked[0], QUALITIES[LEGACY]).label}"


def measured():
    """{preset: {"cost": per-sample time / plain ramp's, "ratio": equal-time
    RMSE / plain ramp's (16 spp), "scenes": ...}} from filter_quality.json,
    or {} when the benchmark has not written it."""
    try:
        with open(TABLE_PATH) as f:
            return json.load(f).get("presets", {})
    except (OSError, ValueError):
        return {}
