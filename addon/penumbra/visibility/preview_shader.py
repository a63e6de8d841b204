"""The GLSL of the GPU preview (gpu_preview.py), generated per SH order,
lobe count and BRDF, and the data it reads: the uniform block's bytes and
the packed vertex attributes. Plain Python and numpy: no bpy, no gpu, so
every Blender (and a test without a GPU) can build and check it.

The vertex shader is core/sh/pose_shading.cpp's per-vertex arithmetic, in
float (docs/sh-engine.md has the derivation): the frame (t, b, n); z' = n,
or for Phong r = 2(n·w) n − w with w towards the scene camera (clamped to
the horizon when the camera is behind the surface, r = n where undefined);
F' = Rz(φ) Ry(θ) taking z to z' (φ = 0 at the poles); each lobe's axis
turned into F' and expanded with paper Eq. 1; u = T v block by block
(sh/brdf_operator.hpp); u back to world with D(F') = Dz(φ) Xᵀ Dz(θ) X; the
dot with the lighting, plus the translucent back lobe y(n)·back. Invalid
vertices (zero or non-finite normal, tangent along the normal, non-finite
bands or position, a zero axis with non-zero bands) shade to 0.

Constants of an order are written into the source: the Legendre recurrence
of sh/basis.cpp, the non-zeros of the quarter turn X = D(Rx(90°)) (from the
core's SH rotation, as sh::PoseShader builds it), the ZH scales sqrt(4π/(2l+1))
and the AO weights √(4π) T_d[00, l0]. What changes between draws is in the
uniform block PenumbraShading: the RGB lighting, the back lobe folded into
it, T's blocks (diffuse, or Phong for an exponent) and the camera.

Vertex attributes: p_position, p_normal, p_tangent (vec3, world) and
p_lobe0.. (vec4): per lobe its local axis then its `order` band
coefficients, lobes one after another, zero-padded to whole vec4s. At the
largest model (order 8, 4 lobes: 44 floats) that is 14 of the 16 vertex
attributes OpenGL guarantees.
"""

import math

import numpy as np

from .. import native
from . import model_shader

# The largest model a bake makes, and so the largest the preview draws: the
# core's limits (core/visibility/order_limit.hpp, zh_fit.hpp). None without
# the compiled core, when there is no model to draw.
MAX_ORDER = native.module.visibility.MAX_ORDER if native.module else None
MAX_LOBES = native.module.visibility.MAX_LOBES if native.module else None
MODELS = ("diffuse", "phong", "translucent")


def sh_index(l, m):
    return l * (l + 1) + m


def _f(x):
    """A GLSL float literal (9 significant digits: float32 round-trips)."""
    text = format(float(x), ".9g")
    if not any(c in text for c in ".en"):
        text += ".0"
    return text if not text.startswith("-") else f"({text})"


def legendre_coefficients(order):
    """The normalized Legendre recurrence of sh/basis.cpp: (diagonal, first, a, b)."""
    diagonal, first = [0.0] * order, [0.0] * order
    a, b = {}, {}
    product = 1.0
    for m in range(order):
        if m > 0:
            product *= math.sqrt((2.0 * m - 1.0) / (2.0 * m))
        diagonal[m] = math.sqrt((2.0 * m + 1.0) / (4.0 * math.pi)) * product
        first[m] = math.sqrt(2.0 * m + 3.0)
        for l in range(m + 2, order):
            l2, m2, lm1 = float(l * l), float(m * m), l - 1.0
            a[l, m] = math.sqrt((4.0 * l2 - 1.0) / (l2 - m2))
            b[l, m] = math.sqrt((lm1 * lm1 - m2) / (4.0 * lm1 * lm1 - 1.0))
    return diagonal, first, a, b


def quarter_turn(order):
    """X = D(Rx(90°)) at `order`, from the core's SH rotation (as sh::PoseShader builds it)."""
    core = native.require()
    rotation = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
    n = order * order
    x = np.asarray(core.sh.rotate(np.eye(n), rotation), dtype=np.float64).reshape(n, n)
    x[np.abs(x) < 1e-14] = 0.0  # entries that vanish analytically come out at rounding level
    return x


def operator_block_layout(order):
    """Offsets of T's per-|m| blocks in the flat array: block a is (order − a)², row-major."""
    offsets, total = [], 0
    for a in range(order):
        offsets.append(total)
        total += (order - a) ** 2
    return offsets, total


def _eval_function(order):
    """y = SH basis at a unit direction: the recurrence of sh/basis.cpp, unrolled."""
    diagonal, first, a, b = legendre_coefficients(order)
    lines = [f"void sh_eval(vec3 d, out float y[NC])", "{"]
    for m in range(order):
        lines.append(f"  y[{sh_index(m, m)}] = {_f(diagonal[m])};")
        if m + 1 >= order:
            break
        lines.append(f"  y[{sh_index(m + 1, m)}] = {_f(first[m] * diagonal[m])} * d.z;")
        for l in range(m + 2, order):
            lines.append(f"  y[{sh_index(l, m)}] = {_f(a[l, m])} * (d.z * y[{sh_index(l - 1, m)}]"
                         f" - {_f(b[l, m])} * y[{sh_index(l - 2, m)}]);")
    if order > 1:
        # C_m + i S_m = (x + iy)^m.
        lines.append("  float c = 1.0, s = 0.0, c_next;")
        for m in range(1, order):
            lines.append("  c_next = d.x * c - d.y * s; s = d.x * s + d.y * c; c = c_next;")
            for l in range(m, order):
                lines.append(f"  y[{sh_index(l, -m)}] = {_f(math.sqrt(2.0))} * s * y[{sh_index(l, m)}];")
                lines.append(f"  y[{sh_index(l, m)}] *= {_f(math.sqrt(2.0))} * c;")
    lines.append("}")
    return "\n".join(lines)


def _normal_zonal_function(order):
    """v_l0 in the normal frame of one lobe (Phong's visibility output): the m = 0 recurrence in z."""
    diagonal, first, a, b = legendre_coefficients(order)
    lines = ["void zonal_eval(float z, out float p[ORDER])", "{", f"  p[0] = {_f(diagonal[0])};"]
    if order > 1:
        lines.append(f"  p[1] = {_f(first[0] * diagonal[0])} * z;")
    for l in range(2, order):
        lines.append(f"  p[{l}] = {_f(a[l, 0])} * (z * p[{l - 1}] - {_f(b[l, 0])} * p[{l - 2}]);")
    lines.append("}")
    return "\n".join(lines)


def _rotate_z_function(order):
    """In place: coefficients turned by Rz(α), (cos α, sin α) = (c, s)."""
    lines = ["void rotate_z(float c, float s, inout float w[NC])", "{"]
    if order > 1:
        lines.append("  float cm = c, sm = s, c_next, p, q;")
        for m in range(1, order):
            if m > 1:
                lines.append("  c_next = cm * c - sm * s; sm = sm * c + cm * s; cm = c_next;")
            for l in range(m, order):
                i, j = sh_index(l, m), sh_index(l, -m)
                lines.append(f"  p = w[{i}]; q = w[{j}]; w[{i}] = p * cm - q * sm; w[{j}] = p * sm + q * cm;")
    lines.append("}")
    return "\n".join(lines)


def _sparse_product_function(name, matrix):
    """out = matrix · in, the non-zeros written out."""
    n = matrix.shape[0]
    lines = [f"void {name}(in float a[NC], out float r[NC])", "{"]
    for row in range(n):
        terms = [f"{_f(matrix[row, col])} * a[{col}]" for col in range(n) if matrix[row, col] != 0.0]
        lines.append(f"  r[{row}] = {' + '.join(terms) if terms else '0.0'};")
    lines.append("}")
    return "\n".join(lines)


def _operator_function(order):
    """u = T v, T in per-|m| blocks from the uniform block (4 floats per vec4)."""
    offsets, _ = operator_block_layout(order)
    lines = ["void apply_operator(in float v[NC], out float u[NC])", "{"]
    for m in range(-(order - 1), order):
        a = abs(m)
        size = order - a
        for l in range(size):
            terms = []
            for lp in range(size):
                k = offsets[a] + l * size + lp
                terms.append(f"shading.blocks[{k // 4}].{'xyzw'[k % 4]} * v[{sh_index(lp + a, m)}]")
            lines.append(f"  u[{sh_index(l + a, m)}] = {' + '.join(terms)};")
    lines.append("}")
    return "\n".join(lines)


def lobe_vec4_count(order, lobes):
    return (lobes * (3 + order) + 3) // 4


def check_configuration(order, lobes, model):
    """ValueError unless the preview can draw this model (see the module's limits)."""
    native.require()
    if not 1 <= order <= MAX_ORDER:
        raise ValueError(f"the GPU preview draws SH orders 1 to {MAX_ORDER}, the model has order {order}")
    if not 1 <= lobes <= MAX_LOBES:
        raise ValueError(f"the GPU preview draws 1 to {MAX_LOBES} lobes per vertex, the model has {lobes}")
    if model not in MODELS:
        raise ValueError(f"the GPU preview draws the BRDFs {', '.join(MODELS)}, not '{model}'")


def uniform_block_source(order):
    _, total = operator_block_layout(order)
    n = order * order
    return (f"struct PenumbraShading {{\n"
            f"  vec4 lighting[{n}];\n"        # RGB world radiance SH
            f"  vec4 back[{n}];\n"            # translucent back lobe folded into the lighting
            f"  vec4 blocks[{(total + 3) // 4}];\n"  # T's per-|m| blocks, 4 floats a vec4
            f"  vec4 camera;\n"               # xyz: the scene camera (Phong's viewer)
            f"}};\n")


# main()'s fixed parts. The vertex frame: n, then t Gram–Schmidt'ed against
# it (a tangent within 1e-6 rad of n is unusable).
_FRAME_GLSL = [
    "  vec3 n = p_normal, t = p_tangent;",
    "  float nn = dot(n, n);",
    "  bool n_ok = finite3(n) && nn > 0.0 && !isinf(nn);",
    "  n = n_ok ? n * inversesqrt(n_ok ? nn : 1.0) : vec3(0.0, 0.0, 1.0);",
    "  float tt = dot(t, t);",
    "  bool t_ok = finite3(t) && tt > 0.0 && !isinf(tt);",
    "  t = t_ok ? t * inversesqrt(t_ok ? tt : 1.0) : vec3(1.0, 0.0, 0.0);",
    "  t -= dot(t, n) * n;",
    "  tt = dot(t, t);",
    "  valid = n_ok && t_ok && tt > 1e-12;",
    "  t = valid ? t * inversesqrt(valid ? tt : 1.0) : vec3(1.0, 0.0, 0.0);",
    "  n = valid ? n : vec3(0.0, 0.0, 1.0);",
    "  vec3 b = cross(n, t);",
    "  vec3 zp = n;",
]
# Phong's lobe axis z' = r = 2(n·w) n − w, w towards the camera; clamped to
# the horizon behind the surface.
_PHONG_AXIS_GLSL = [
    "  vec3 w = shading.camera.xyz - p_position;",
    "  bool position_ok = finite3(w);",
    "  valid = valid && position_ok;",
    "  float ww = dot(w, w);",
    "  bool has_view = position_ok && ww > 0.0 && !isinf(ww);",
    "  w = has_view ? w * inversesqrt(has_view ? ww : 1.0) : n;",
    "  float cosine = dot(n, w);",
    "  vec3 h = w - cosine * n;",
    "  float hh = dot(h, h);",
    "  bool horizon = hh > 1e-24;",
    "  h = horizon ? h * inversesqrt(horizon ? hh : 1.0) : n;",
    "  vec3 r = 2.0 * cosine * n - w;",
    "  r = cosine < 0.0 ? (horizon ? -h : n) : r;",
    "  float rr = dot(r, r);",
    "  r = rr > 0.0 ? r * inversesqrt(rr > 0.0 ? rr : 1.0) : n;",
    "  zp = has_view ? r : n;",
]
# F' = Rz(φ) Ry(θ), F' e_z = z'; at the poles φ is free (0). Then the locals.
_ROTATION_GLSL = [
    "  float ct = zp.z, st = sqrt(zp.x * zp.x + zp.y * zp.y);",
    "  bool pole = !(st > 0.0);",
    "  float cp = pole ? 1.0 : zp.x / st, sp = pole ? 0.0 : zp.y / st;",
    "  vec3 e1 = vec3(cp * ct, sp * ct, -st), e2 = vec3(-sp, cp, 0.0), e3 = vec3(cp * st, sp * st, ct);",
    "  mat3 frame = mat3(t, b, n);",
    "  float v[NC], y[NC], u[NC];",
    "  for (int i = 0; i < NC; i++) { v[i] = 0.0; }",
    "  float normal_zonal[ORDER], p[ORDER];",
    "  for (int l = 0; l < ORDER; l++) { normal_zonal[l] = 0.0; }",
    "  vec3 a;",
    "  float g[ORDER];",
    "  bool bands_finite, bands_zero, axis_ok, use;",
    "  float aa;",
]
# A lobe's checks: a zero axis with zero bands is an unused lobe; anything
# else zero or non-finite makes the vertex invalid.
_LOBE_CHECK_GLSL = [
    "  bands_finite = true; bands_zero = true;",
    "  for (int l = 0; l < ORDER; l++) {",
    "    bands_finite = bands_finite && !isnan(g[l]) && !isinf(g[l]);",
    "    bands_zero = bands_zero && g[l] == 0.0;",
    "  }",
    "  aa = dot(a, a);",
    "  axis_ok = finite3(a) && aa > 0.0 && !isinf(aa);",
    "  a = axis_ok ? a * inversesqrt(axis_ok ? aa : 1.0) : vec3(0.0, 0.0, 1.0);",
    "  valid = valid && bands_finite && (axis_ok || bands_zero);",
    "  use = axis_ok && bands_finite && valid;",
    "  for (int l = 0; l < ORDER; l++) { g[l] = use ? g[l] : 0.0; }",
    "  sh_eval(vec3(dot(e1, frame * a), dot(e2, frame * a), dot(e3, frame * a)), y);",
]
# Step 4: u = T v. Step 5: back to world, D(F') = Dz(φ) Xᵀ Dz(θ) X, then the
# dot with the lighting.
_TO_WORLD_GLSL = [
    "  apply_operator(v, u);",
    "  quarter_turn(u, y);",
    "  rotate_z(ct, st, y);",
    "  quarter_turn_t(y, u);",
    "  rotate_z(cp, sp, u);",
    "  vec3 rgb = vec3(0.0);",
    "  for (int i = 0; i < NC; i++) { rgb += shading.lighting[i].rgb * u[i]; }",
]
# One vertex per pixel of the offscreen buffer: row-major from the bottom-left.
_READBACK_GLSL = [
    "  int column = gl_VertexID % int(readback_size.x), row_index = gl_VertexID / int(readback_size.x);",
    "  gl_Position = vec4((float(column) + 0.5) * 2.0 / readback_size.x - 1.0,",
    "                     (float(row_index) + 0.5) * 2.0 / readback_size.y - 1.0, 0.0, 1.0);",
    "  gl_PointSize = 1.0;",
    "  result = vec4(rgb, visibility);",
]
_VIEWPORT_GLSL = [
    "  gl_Position = ViewProjectionMatrix * vec4(p_position, 1.0);",
    "  gl_Position.z -= depth_bias * gl_Position.w;",
    "  shade = max(rgb, vec3(0.0));",
]


def vertex_source(order, lobes, model, readback, model_texture_width=None):
    """The GLSL of the vertex shader's functions and main() for one
    configuration. model_texture_width None: the lobes and the frame come as
    vertex attributes; else the shader evaluates the pose model from its
    textures at that width (model_shader.py)."""
    check_configuration(order, lobes, model)
    x = quarter_turn(order)
    from_model = model_texture_width is not None
    lines = [
        *([model_shader.helper_source(model_texture_width)] if from_model else []),
        _eval_function(order), _normal_zonal_function(order), _rotate_z_function(order),
        _sparse_product_function("quarter_turn", x), _sparse_product_function("quarter_turn_t", x.T),
        _operator_function(order),
        "bool finite3(vec3 a) { return !any(isnan(a)) && !any(isinf(a)); }",
        "void main()",
        "{",
        "  bool valid = true;",
        *(model_shader.main_prologue(order, lobes) if from_model else []),
        *_FRAME_GLSL,
        *(_PHONG_AXIS_GLSL if model == "phong" else []),
        *_ROTATION_GLSL,
    ]
    for lobe in range(lobes):
        lines += _lobe_glsl(order, lobes, model, lobe, from_model)
    lines += _TO_WORLD_GLSL
    if model == "translucent":
        lines += ["  sh_eval(n, y);",
                  "  for (int i = 0; i < NC; i++) { rgb += shading.back[i].rgb * y[i]; }"]
    ao_weight = [math.sqrt(4.0 * math.pi) * w for w in _diffuse_block0(order)[0]]
    zonal = "normal_zonal[{l}]" if model == "phong" else "v[{i}]"
    terms = [f"{_f(ao_weight[l])} * " + zonal.format(l=l, i=sh_index(l, 0)) for l in range(order)]
    lines.append(f"  float visibility = {' + '.join(terms)};")
    lines += ["  rgb = valid ? rgb : vec3(0.0);", "  visibility = valid ? visibility : 0.0;"]
    lines += _READBACK_GLSL if readback else _VIEWPORT_GLSL
    lines.append("}")
    return "\n".join(lines)


def _lobe_glsl(order, lobes, model, lobe, from_model=False):
    """main()'s lines for one ZH lobe: unpack, check, and add its SH (and, for
    Phong, its zonal part about the normal)."""
    zh_scale = [math.sqrt(4.0 * math.pi / (2 * l + 1)) for l in range(order)]
    packed = [f"p_lobe{k}" for k in range(lobe_vec4_count(order, lobes))]

    def packed_value(k):
        return f"{packed[k // 4]}.{'xyzw'[k % 4]}"

    base = lobe * (3 + order)
    if from_model:
        lines = model_shader.lobe_from_parameters(order, lobe)
    else:
        lines = [f"  // lobe {lobe}: axis (local t, b, n) and band coefficients",
                 f"  a = vec3({packed_value(base)}, {packed_value(base + 1)}, {packed_value(base + 2)});"]
        lines += [f"  g[{l}] = {packed_value(base + 3 + l)};" for l in range(order)]
    lines += _LOBE_CHECK_GLSL
    for l in range(order):
        lines.append(f"  for (int i = {l * l}; i < {(l + 1) * (l + 1)}; i++) "
                     f"{{ v[i] += {_f(zh_scale[l])} * g[{l}] * y[i]; }}")
    if model == "phong":
        lines.append("  zonal_eval(a.z, p);")
        for l in range(order):
            lines.append(f"  normal_zonal[{l}] += {_f(zh_scale[l])} * g[{l}] * p[{l}];")
    return lines


FRAGMENT_READBACK = "void main()\n{\n  fragColor = result;\n}\n"
# Scene-linear to the sRGB curve for display (not the scene's view transform).
FRAGMENT_VIEWPORT = """vec3 srgb_encode(vec3 c)
{
  c = clamp(c, 0.0, 1.0);
  return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}
void main()
{
  fragColor = vec4(srgb_encode(shade), 1.0);
}
"""


def _diffuse_block0(order):
    """T_d's m = 0 block: (order, order), from the core's diffuse operator."""
    dense = np.asarray(native.require().sh.diffuse_operator(order), dtype=np.float64)
    zonal = [sh_index(l, 0) for l in range(order)]
    return dense[np.ix_(zonal, zonal)]


# Per-call uniforms and per-vertex attributes ----------------------------------

def operator_blocks(order, model, phong_exponent):
    """T's per-|m| blocks, flattened as sh::PoseShader lays them out (block a row-major)."""
    core = native.require()
    dense = np.asarray(core.sh.phong_operator(order, phong_exponent) if model == "phong"
                       else core.sh.diffuse_operator(order), dtype=np.float64)
    _, total = operator_block_layout(order)
    flat = np.zeros(total)
    at = 0
    for a in range(order):
        rows = [sh_index(l, a) for l in range(a, order)]
        block = dense[np.ix_(rows, rows)]
        flat[at:at + block.size] = block.reshape(-1)
        at += block.size
    return flat


def uniform_data(order, lighting, model="diffuse", phong_exponent=16.0, camera=(0.0, 0.0, 0.0),
                 transmission=(0.5, 0.5, 0.5)):
    """The uniform block's bytes (std140: arrays of vec4), see uniform_block_source."""
    lighting = np.asarray(lighting, dtype=np.float64).reshape(order * order, 3)
    n = order * order
    blocks = operator_blocks(order, model, phong_exponent)
    # Translucent back lobe, folded into the lighting as sh::PoseShader does:
    # back[lm] = transmission (−1)^l sqrt(4π/(2l+1)) h_l lighting[lm], h_l = √(4π) T_d[l0, 00].
    diffuse0 = _diffuse_block0(order)
    back = np.zeros((n, 3))
    for l in range(order):
        h = math.sqrt(4.0 * math.pi) * diffuse0[l, 0]
        scale = (-1.0) ** l * math.sqrt(4.0 * math.pi / (2 * l + 1)) * h
        for m in range(-l, l + 1):
            back[sh_index(l, m)] = np.asarray(transmission, dtype=np.float64) * scale * lighting[sh_index(l, m)]
    vec4_blocks = (blocks.size + 3) // 4
    data = np.zeros((2 * n + vec4_blocks + 1, 4), dtype=np.float32)
    data[:n, :3] = lighting
    data[n:2 * n, :3] = back
    flat = np.zeros(vec4_blocks * 4)
    flat[:blocks.size] = blocks
    data[2 * n:2 * n + vec4_blocks] = flat.reshape(-1, 4)
    data[-1, :3] = np.asarray(camera, dtype=np.float64)
    return data.tobytes()


def pack_vertex_data(positions, normals, tangents, axes, bands):
    """Per-vertex attributes, float32 and contiguous: {'p_position', 'p_normal',
    'p_tangent': (V, 3), 'p_lobe<k>': (V, 4)}; axes (V, C, 3), bands (V, C, order)."""
    axes = np.asarray(axes, dtype=np.float32)
    bands = np.asarray(bands, dtype=np.float32)
    vertex_count, lobes, order = bands.shape
    per_vertex = lobes * (3 + order)
    count = lobe_vec4_count(order, lobes)
    packed = np.zeros((vertex_count, 4 * count), dtype=np.float32)
    packed[:, :per_vertex] = np.concatenate([axes, bands], axis=2).reshape(vertex_count, per_vertex)
    data = {"p_position": np.ascontiguousarray(positions, dtype=np.float32),
            "p_normal": np.ascontiguousarray(normals, dtype=np.float32),
            "p_tangent": np.ascontiguousarray(tangents, dtype=np.float32)}
    for k in range(count):
        data[f"p_lobe{k}"] = np.ascontiguousarray(packed[:, 4 * k:4 * k + 4])
    return data
