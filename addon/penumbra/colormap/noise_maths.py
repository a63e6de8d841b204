"""The maths of the noise filter, free of bpy (docs/colormap.md): the noise
as a sum of Detail-0 octaves (NoiseModel, read from a node by
noise_model.read_noise), Blender's hash that places the distortion's
offsets, the weights of Blender's normalized fBm, and where the Noise
Filter puts its taps and how many it may spend."""

import dataclasses
import math
import statistics
import struct

_AXES = {"1D": 1, "2D": 2, "3D": 3, "4D": 4}


@dataclasses.dataclass(frozen=True)
class NoiseModel:
    """value = offset + Σ c_i (Fac_i − 0.5), Fac_i the normalized Detail-0
    Noise Texture at Scale·lacunarity^i on the distorted position.

    scale / w: the input's value, None when it is driven (then scale_from /
    w_from hold the output socket that really drives it, node_links.feed, in
    the ramp's tree, which the filter takes as a link; vector_from likewise,
    None for the implicit coordinates)."""
    node_name: str
    node_type: str              # NOISE or MUSGRAVE
    noise_type: str             # 'FBM', 'MULTIFRACTAL', ... (Blender's enum)
    dimensions: str             # '1D', '2D', '3D', '4D'
    offset: float
    coefficients: tuple
    lacunarity: float
    distortion: float
    scale: object = None
    w: object = None
    vector_from: object = None
    scale_from: object = None
    w_from: object = None

    @property
    def axes(self):
        return _AXES[self.dimensions]

    @property
    def uses_vector(self):
        return self.dimensions != "1D"

    @property
    def uses_w(self):
        return self.dimensions in ("1D", "4D")

    @property
    def mean_min(self):
        """Lowest value the noise (and its mean) can take: every octave at −1."""
        return self.offset - 0.5 * sum(abs(c) for c in self.coefficients)

    @property
    def mean_max(self):
        return self.offset + 0.5 * sum(abs(c) for c in self.coefficients)

    @property
    def total_weight_sq(self):
        """Σ c_i²: the value's variance is this times one octave's."""
        return sum(c * c for c in self.coefficients)

    def distortion_offsets(self):
        """Blender's constant offsets o_k (k < axes), each a tuple of `axes`
        floats: component k of p moves by distortion·snoise(p + o_k)."""
        return tuple(random_offset(float(k), self.axes) for k in range(self.axes))


# ---- Blender's hash (Cycles util/hash.h, blenlib BLI_hash.hh) -------------

def _rot(x, k):
    return ((x << k) | (x >> (32 - k))) & 0xFFFFFFFF


# Jenkins lookup3's final(a, b, c): each step x ^= y; x -= rot(y, k).
_FINAL_STEPS = ((2, 1, 14), (0, 2, 11), (1, 0, 25), (2, 1, 16), (0, 2, 4), (1, 0, 14), (2, 1, 24))


def _final(a, b, c):
    """Jenkins lookup3 final(a, b, c); returns c."""
    v = [a, b, c]
    for x, y, k in _FINAL_STEPS:
        v[x] ^= v[y]
        v[x] = (v[x] - _rot(v[y], k)) & 0xFFFFFFFF
    return v[2]


def hash_uint(kx):
    a = b = c = (0xDEADBEEF + (1 << 2) + 13) & 0xFFFFFFFF
    a = (a + kx) & 0xFFFFFFFF
    return _final(a, b, c)


def hash_uint2(kx, ky):
    a = b = c = (0xDEADBEEF + (2 << 2) + 13) & 0xFFFFFFFF
    b = (b + ky) & 0xFFFFFFFF
    a = (a + kx) & 0xFFFFFFFF
    return _final(a, b, c)


def _float_bits(x):
    return struct.unpack("<I", struct.pack("<f", x))[0]


def _f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


def _offset_component(hashed):
    """100 + 100·uint_to_float_incl(hashed) in float arithmetic:
    (float)n · (1 / (float)0xFFFFFFFF), and 1/(float)0xFFFFFFFF is 2^-32."""
    unit = _f32(_f32(float(hashed)) * 2.0 ** -32)
    return _f32(100.0 + _f32(unit * 100.0))


def random_offset(seed, axes):
    """random_float_offset(seed) (1D: a 1-tuple) or random_float{2,3,4}_offset
    (noisetex.h): component k = 100 + 100·hash_float2_to_float(seed, k)."""
    if axes == 1:
        return (_offset_component(hash_uint(_float_bits(seed))),)
    return tuple(_offset_component(hash_uint2(_float_bits(seed), _float_bits(float(k)))) for k in range(axes))


# ---- octave weights --------------------------------------------------------

def octave_weights(detail, roughness, blender_version):
    """Weights w_i of Blender's normalized fBm: Fac = Σ w_i Fac_i, Fac_i the
    Noise Texture at Detail 0 and Scale·lacunarity^i (Σ w_i = 1). Integer
    detail n: w_i = r^i / M_n (M_n = Σ_{k<=n} r^k); fractional detail n + f
    blends the n- and (n+1)-octave sums: w_i = r^i ((1−f)/M_n + f/M_{n+1}),
    w_{n+1} = f r^{n+1} / M_{n+1} (Cycles' noise_fbm, Blender 3.4 and 4.x;
    3.4 clamps roughness to [0, 1], detail to [0, 15]). blender_version:
    bpy.app.version, a tuple."""
    detail = min(max(float(detail), 0.0), 15.0)
    r = float(roughness)
    if tuple(blender_version) < (4, 0, 0):
        r = min(max(r, 0.0), 1.0)
    n = int(math.floor(detail))
    f = detail - n

    def amplitude_sum(k):
        return sum(r ** i for i in range(k + 1))

    weights = [r ** i * ((1.0 - f) / amplitude_sum(n) + f / amplitude_sum(n + 1)) for i in range(n + 1)]
    if f > 0.0:
        weights.append(f * r ** (n + 1) / amplitude_sum(n + 1))
    return weights


def fbm_detail_roughness(coefficients):
    """(Detail, Roughness) whose normalized fBm weights (octave_weights) are
    `coefficients`, or None when none are (fewer than three octaves, where
    Roughness is not determined, or a roughness of 0). The band-limited
    filter (native_filter.py) rebuilds the noise from them."""
    if len(coefficients) < 3 or coefficients[0] <= 0.0 or coefficients[1] <= 0.0:
        return None
    r = coefficients[1] / coefficients[0]
    whole = len(coefficients) - 1
    partial = len(coefficients) - 2
    fraction = coefficients[-1] * sum(r ** i for i in range(partial + 2)) / r ** (partial + 1)
    for detail in (float(whole), partial + fraction):
        if not 0.0 <= detail <= 15.0:
            continue
        weights = octave_weights(detail, r, (4, 0, 0))
        if len(weights) == len(coefficients) and all(abs(a - b) <= 1e-6 * max(abs(b), 1e-3)
                                                      for a, b in zip(weights, coefficients)):
            return detail, r
    return None


def band_limited_terms(x, coefficients, detail, r, lacunarity, total_var, bias):
    """(D', k·g₀, σ) at x: Blender's normalized fBm at Detail D' = n + f is
    0.5 + Σ_{i≤n} r^i α s_i/2 + f r^(n+1) s_(n+1)/(2 M_(n+1)), α = (1 − f)/M_n
    + f/M_(n+1), M_m = Σ_{i≤m} r^i (fractal_noise.h, 3.4 and 4.x); times
    k = c_0/α its octaves i ≤ n get the model's weights c_i = c_0 r^i and
    octave n + 1 a weight w ≤ c_(n+1). The estimate is shrunk by octave 0's
    g₀ = (1 + L^(−2x))^(−½) (noise_maths.point_shrinkage: Detail 0 still
    evaluates octave 0, aliased at the horizon). σ² = V₀ (E + (Σc² − E)(1 −
    g₀²)), E = Σ_(i>n+1) c_i² + (c_(n+1) − w)²: what is left out, plus what
    the shrunk octaves lose. D' = x + bias in [0, D]. The band-limited
    filter (native_filter.py) bakes these into its curves."""
    cut = min(max(x + bias, 0.0), detail)
    n = int(math.floor(cut))
    f = cut - n
    if n >= len(coefficients) - 1:
        n, f = len(coefficients) - 1, 0.0

    def amplitude_sum(m):
        return sum(r ** i for i in range(m + 1))
    alpha = (1.0 - f) / amplitude_sum(n) + f / amplitude_sum(n + 1)
    k = coefficients[0] / alpha
    w = k * f * r ** (n + 1) / amplitude_sum(n + 1)
    left = sum(c * c for c in coefficients[n + 2:])
    if n + 1 < len(coefficients):
        left += (coefficients[n + 1] - w) ** 2
    total = sum(c * c for c in coefficients)
    g0 = (1.0 + math.exp(min(-2.0 * x * math.log(lacunarity), 700.0))) ** -0.5
    variance = total_var * (left + (total - left) * (1.0 - g0 * g0))
    return cut, k * g0, math.sqrt(max(variance, 0.0))


# ---- taps of the Noise Filter ------------------------------------------------

# Components of the Gaussian mixture the Noise Filter hands the filtered ramp
# (docs/colormap.md, "A mixture of Gaussians"): the taps in four equal groups.
MIXTURE_COMPONENTS = 4
# Noise evaluations per shading point the Noise Filter may spend in EEVEE:
# llvmpipe (and GPU drivers) compile the whole material as one shader, and
# its memory grows faster than linearly with the Noise nodes in it (Blender
# 3.4, llvmpipe, 48×27, 1 sample, peak memory and first render: 16 Noise
# evaluations 1.1 GiB, 6 s; 48 3.3 GiB, 42 s; 80 6.8 GiB, 88 s; Detail 8
# with Distortion at 16 taps, 192, went past 24 GiB). Detail 4 gets 8 taps
# (40: 2.5 GiB, 25 s), Detail 8 with Distortion 4 (48: 3.3 GiB).
EEVEE_NOISE_BUDGET = 48
TAP_COUNTS = (16, 8, 4)


def major_taps(count):
    """Tap positions along the footprint's major axis, in kernel standard
    deviations: the Gaussian's quantiles at (k + 1/2)/count scaled to unit
    variance (equal weights). With two taps (±1) along the minor axis they
    make 2·count taps."""
    quantiles = [statistics.NormalDist().inv_cdf((k + 0.5) / count) for k in range(count)]
    rms = math.sqrt(sum(q * q for q in quantiles) / count)
    return tuple(q / rms for q in quantiles)


# One octave's correlation length at Scale 1 (noise units), as a Gaussian
# ρ(d) = exp(−d²/2l²): with it 1 − q = ((1 + 2s²/l²)(1 + 2s²e²/l²))^(−1/2)
# matches the measured q(s, e) table of noise_statistics.json to 0.012 RMS
# (0.04 at most) in 4.5 and 3.4 (tests/python/colormap/test_point_filter.py).
# The one-evaluation filter (point_filter.py) needs no table with it.
OCTAVE_CORRELATION_LENGTH = 0.426

MAJOR_TAPS = major_taps(8)
TAP_COUNT = 2 * len(MAJOR_TAPS)


def point_shrinkage(minor, major, octave, lacunarity):
    """g = E_kernel[ρ] of octave `octave` under a Gaussian kernel of standard
    deviations (minor, major) in noise units at Scale 1: the weight the
    one-evaluation filter gives its value (point_filter.py's nodes compute
    the same); 1 − g² is the variance it carries."""
    growth = (lacunarity ** octave / OCTAVE_CORRELATION_LENGTH) ** 2
    return ((1.0 + minor * minor * growth) * (1.0 + major * major * growth)) ** -0.5


def noise_evaluations_per_tap(model):
    """Noise Textures one tap evaluates: one per octave, plus one per axis of
    the distortion's offset."""
    return len(model.coefficients) + (model.axes if model.distortion != 0.0 else 0)


def tap_count(model, engine):
    """Taps of the Noise Filter for a render engine: 16 in Cycles; in EEVEE
    the most of TAP_COUNTS within EEVEE_NOISE_BUDGET Noise evaluations (at
    least 4)."""
    if engine not in ("BLENDER_EEVEE", "BLENDER_EEVEE_NEXT"):
        return TAP_COUNTS[0]
    per_tap = noise_evaluations_per_tap(model)
    return next((n for n in TAP_COUNTS if n * per_tap <= EEVEE_NOISE_BUDGET), TAP_COUNTS[-1])
