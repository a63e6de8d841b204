// The hot loop of the pose shader (sh/pose_shading.hpp), compiled once per
// SIMD target by Highway's foreach_target (SSE4, AVX2, AVX-512, and EMU128 as
// the one-lane scalar reference) and chosen at run time by its dynamic
// dispatch, so a portable (x86-64-v2) build still runs AVX2/AVX-512 code
// where the CPU has it.
//
// Layout: vertices go in batches of one SIMD register of the precision S the
// kernel computes in, that of the buffers (double: 1 lane for the scalar
// reference, 2 with SSE4, 4 with AVX2, 8 with AVX-512; float: 1, 4, 8, 16).
// Every per-vertex quantity is such a lane vector (common/simd_lanes-inl.h:
// GCC/Clang vector extensions, which Highway's per-target `#pragma GCC
// target` turns into that target's instructions), so every step is the same straight-line
// arithmetic on all lanes with constants (T, X, lighting) shared by the
// batch, and validity is a lane mask instead of a branch. The order is a
// template parameter for orders 1–8 (fully unrolled) and a runtime value
// above. Compiled with -fno-math-errno (a lane square root is one vector
// instruction).

#include "common/simd_compiled_targets.hpp"  // before any Highway header
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "sh/pose_shading_kernel.cpp"
#include <hwy/foreach_target.h>  // re-includes this file once per target
#include <hwy/highway.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <type_traits>
#include <vector>

#include "common/simd_lanes-inl.h"
#include "sh/basis.hpp"
#include "sh/pose_shading_setup.hpp"

HWY_BEFORE_NAMESPACE();
namespace penumbra::sh::detail::HWY_NAMESPACE {

using namespace simd::HWY_NAMESPACE;

// Squared lengths at or below count as zero (lengths ~1e-150 in double,
// ~1e-15 in float).
template <typename S>
constexpr S tiny_squared = S(1e-30f);
template <>
constexpr double tiny_squared<double> = 1e-300;

// The steps of shading one batch of vertices, in the order shade_range
// calls them (paper §4.3 steps 2–5, docs/sh-engine.md), each forced inline
// (PENUMBRA_LANES_INLINE) so the batch stays one straight-line block in
// registers.
// (x, y, z) ← unit vector in lanes where it is finite and its squared length
// lies in (tiny_squared<S>, inf); returns that mask and sets (x, y, z) to the
// fallback (fx, fy, fz) in the other lanes.
template <typename S, typename F>
PENUMBRA_LANES_INLINE Mask<S> normalize_lanes(Vec<S>& x, Vec<S>& y, Vec<S>& z, const F& fx, const F& fy,
                                              const F& fz) {
    const Vec<S> squared = x * x + y * y + z * z;
    const Mask<S> ok = finite(squared) & (squared > tiny_squared<S>);
    const Vec<S> inverse_length = S(1) / sqrt_lanes(ok ? squared : splat<S>(1));
    const Vec<S> zero{};
    x = ok ? x * inverse_length : zero + fx;
    y = ok ? y * inverse_length : zero + fy;
    z = ok ? z * inverse_length : zero + fz;
    return ok;
}

// y_i(x, y, z) for unit directions in every lane: the Cartesian recurrence of
// sh/basis.cpp (Legendre in z by sh/legendre.hpp, then (x + iy)^m).
template <typename S, int kOrder>
PENUMBRA_LANES_INLINE void eval_lanes(const PoseShadingSetup<S>& setup, const Vec<S>& x, const Vec<S>& y,
                                      const Vec<S>& z, Vec<S>* out) {
    const int order = kOrder ? kOrder : setup.order;
    for (int m = 0; m < order; ++m) {
        out[sh_index(m, m)] = splat<S>(setup.legendre_diagonal[m]);
        if (m + 1 >= order) break;
        out[sh_index(m + 1, m)] = setup.legendre_first[m] * z * setup.legendre_diagonal[m];
        for (int l = m + 2; l < order; ++l) {
            const int i = sh_index(l, m);
            out[i] = setup.legendre_a[i] * (z * out[sh_index(l - 1, m)] - setup.legendre_b[i] * out[sh_index(l - 2, m)]);
        }
    }
    // C_m + i S_m = (x + iy)^m.
    Vec<S> c = splat<S>(1), s = splat<S>(0);
    const S sqrt2 = std::numbers::sqrt2_v<S>;
    for (int m = 1; m < order; ++m) {
        const Vec<S> c_next = x * c - y * s;
        s = x * s + y * c;
        c = c_next;
        const Vec<S> sc = sqrt2 * c, ss = sqrt2 * s;
        for (int l = m; l < order; ++l) {
            const Vec<S> p = out[sh_index(l, m)];
            out[sh_index(l, -m)] = p * ss;
            out[sh_index(l, m)] = p * sc;
        }
    }
}

// v_lm += scale_l y_lm(x, y, z): eval_lanes's recurrence, each term added to
// v as soon as it is known, so no array of y_lm is held (fewer registers
// spilled to the stack).
template <typename S, int kOrder>
PENUMBRA_LANES_INLINE void accumulate_lobe_lanes(const PoseShadingSetup<S>& setup, const Vec<S>& x, const Vec<S>& y,
                                                 const Vec<S>& z, const Vec<S>* scale, Vec<S>* v) {
    const int order = kOrder ? kOrder : setup.order;
    const S sqrt2 = std::numbers::sqrt2_v<S>;
    Vec<S> c = splat<S>(1), s = splat<S>(0);  // C_m + i S_m = (x + iy)^m
    for (int m = 0; m < order; ++m) {
        if (m > 0) {
            const Vec<S> c_next = x * c - y * s;
            s = x * s + y * c;
            c = c_next;
        }
        const Vec<S> sc = sqrt2 * c, ss = sqrt2 * s;
        const auto add = [&](int l, const Vec<S>& p) {
            if (m == 0) {
                v[sh_index(l, 0)] += scale[l] * p;
            } else {
                v[sh_index(l, -m)] += scale[l] * (p * ss);
                v[sh_index(l, m)] += scale[l] * (p * sc);
            }
        };
        Vec<S> before = splat<S>(setup.legendre_diagonal[m]);
        add(m, before);
        if (m + 1 >= order) break;
        Vec<S> last = setup.legendre_first[m] * z * setup.legendre_diagonal[m];
        add(m + 1, last);
        for (int l = m + 2; l < order; ++l) {
            const int i = sh_index(l, m);
            const Vec<S> next = setup.legendre_a[i] * (z * last - setup.legendre_b[i] * before);
            add(l, next);
            before = last;
            last = next;
        }
    }
}

// In place: coefficients of f turned by Rz(α) (g(ω) = f(Rz(α)ᵀ ω)), per lane
// with (cos α, sin α) = (c, s): (p, q) = (w_lm, w_l,−m) →
// (p cos mα − q sin mα, p sin mα + q cos mα).
template <typename S, int kOrder>
PENUMBRA_LANES_INLINE void rotate_z_lanes(int order_runtime, const Vec<S>& c, const Vec<S>& s, Vec<S>* w) {
    const int order = kOrder ? kOrder : order_runtime;
    Vec<S> cm = c, sm = s;
    for (int m = 1; m < order; ++m) {
        if (m > 1) {
            const Vec<S> c_next = cm * c - sm * s;
            sm = sm * c + cm * s;
            cm = c_next;
        }
        for (int l = m; l < order; ++l) {
            const Vec<S> p = w[sh_index(l, m)], q = w[sh_index(l, -m)];
            w[sh_index(l, m)] = p * cm - q * sm;
            w[sh_index(l, -m)] = p * sm + q * cm;
        }
    }
}

// out = X in, X stored row by row with a fixed number of entries per row of
// band l (quarter_turn_width: at most l/2 + 1 are non-zero, the rest padded
// with zeros), so that for a compile-time order every loop unrolls into
// straight-line multiply-adds (28 at order 4) with no branch. (Adding entry
// by entry into out[row] chained every entry through a store and a reload.)
template <typename S, int kOrder>
PENUMBRA_LANES_INLINE void quarter_turn_lanes(int order_runtime, const std::vector<int>& columns,
                                              const std::vector<S>& values, const Vec<S>* in, Vec<S>* out) {
    const int order = kOrder ? kOrder : order_runtime;
    std::size_t e = 0;
    for (int l = 0; l < order; ++l) {
        const int width = quarter_turn_width(l);
        for (int i = l * l; i < (l + 1) * (l + 1); ++i) {
            Vec<S> sum = values[e] * in[columns[e]];
            for (int k = 1; k < width; ++k) sum += values[e + k] * in[columns[e + k]];
            out[i] = sum;
            e += width;
        }
    }
}

// What every batch of a call shares, read from the setup once.
struct Plan {
    int order, lobes;
    bool phong, translucent;
    bool phong_visibility;  // Phong with the visibility output: v_l0 in the normal frame
};

// Vertices start .. start + count − 1 in the lanes; a partial batch repeats
// its last vertex in the spare lanes.
struct Batch {
    std::size_t start;
    int count;
    std::size_t vertex(int k) const { return start + std::min(k, count - 1); }
};

// A vertex's tangent frame (t, b, n) per lane and which lanes are valid.
template <typename S>
struct LaneFrame {
    Vec<S> nx, ny, nz, tx, ty, tz, bx, by, bz;
    Mask<S> valid;
};

// n = normalize(normal), t = the tangent Gram–Schmidt'ed against n, b = n × t
// (header); invalid lanes get (t, b, n) = (x, y, z).
// Rows of a PoseBlock: lanes k = batch.start + k, loaded whole.
PENUMBRA_LANES_INLINE Vec<float> load_row(const float* row, const Batch& batch) {
    Vec<float> v;
    std::memcpy(&v, row + batch.start, sizeof v);
    return v;
}

// (x, y, z) of vertex data: gathered from interleaved triples, or three rows.
template <typename S>
PENUMBRA_LANES_INLINE void load_triples(const S* data, const Batch& batch, Vec<S>& x, Vec<S>& y, Vec<S>& z) {
    for (int k = 0; k < Lanes<S>::count; ++k) {
        const S* p = data + 3 * batch.vertex(k);
        x[k] = p[0]; y[k] = p[1]; z[k] = p[2];
    }
}

PENUMBRA_LANES_INLINE void load_rows(const float* rows, std::size_t stride, const Batch& batch, Vec<float>& x,
                                     Vec<float>& y, Vec<float>& z) {
    x = load_row(rows, batch);
    y = load_row(rows + stride, batch);
    z = load_row(rows + 2 * stride, batch);
}

template <typename S>
PENUMBRA_LANES_INLINE void load_normals_tangents(const PoseBuffers<S>& buffers, const Batch& batch, LaneFrame<S>& f) {
    load_triples<S>(buffers.normals, batch, f.nx, f.ny, f.nz);
    load_triples<S>(buffers.tangents, batch, f.tx, f.ty, f.tz);
}

PENUMBRA_LANES_INLINE void load_normals_tangents(const PoseBlock& block, const Batch& batch, LaneFrame<float>& f) {
    load_rows(block.normals, block.stride, batch, f.nx, f.ny, f.nz);
    load_rows(block.tangents, block.stride, batch, f.tx, f.ty, f.tz);
}

template <typename S, typename Buffers>
PENUMBRA_LANES_INLINE LaneFrame<S> load_frames(const Buffers& buffers, const Batch& batch) {
    LaneFrame<S> f{};
    load_normals_tangents(buffers, batch, f);
    if constexpr (std::is_same_v<Buffers, PoseBlock>) {
        // A block's frames are orthonormal already (PoseBlock's contract).
        f.valid = f.nx == f.nx;
        f.bx = f.ny * f.tz - f.nz * f.ty; f.by = f.nz * f.tx - f.nx * f.tz; f.bz = f.nx * f.ty - f.ny * f.tx;
        return f;
    }
    f.valid = normalize_lanes<S>(f.nx, f.ny, f.nz, S(0), S(0), S(1));
    // Gram–Schmidt; a tangent within 1e-6 rad of n leaves nothing usable.
    f.valid &= normalize_lanes<S>(f.tx, f.ty, f.tz, S(1), S(0), S(0));
    const Vec<S> along = f.tx * f.nx + f.ty * f.ny + f.tz * f.nz;
    f.tx -= along * f.nx; f.ty -= along * f.ny; f.tz -= along * f.nz;
    f.valid &= f.tx * f.tx + f.ty * f.ty + f.tz * f.tz > S(1e-12);
    f.valid &= normalize_lanes<S>(f.tx, f.ty, f.tz, S(1), S(0), S(0));
    const Mask<S> valid = f.valid;
    f.nx = valid ? f.nx : splat<S>(0); f.ny = valid ? f.ny : splat<S>(0); f.nz = valid ? f.nz : splat<S>(1);
    f.tx = valid ? f.tx : splat<S>(1); f.ty = valid ? f.ty : splat<S>(0); f.tz = valid ? f.tz : splat<S>(0);
    f.bx = f.ny * f.tz - f.nz * f.ty; f.by = f.nz * f.tx - f.nx * f.tz; f.bz = f.nx * f.ty - f.ny * f.tx;
    return f;
}

template <typename S>
struct LaneVector {
    Vec<S> x, y, z;
};

// Phong's axis r = 2(n·w) n − w, w = normalize(camera − position), clamped
// to the horizon when n·w < 0; r = n where w or the clamp is undefined. A
// non-finite position makes the lane invalid.
template <typename S>
PENUMBRA_LANES_INLINE void load_positions(const PoseBuffers<S>& buffers, const Batch& batch, Vec<S>& x, Vec<S>& y,
                                          Vec<S>& z) {
    load_triples<S>(buffers.positions, batch, x, y, z);
}

PENUMBRA_LANES_INLINE void load_positions(const PoseBlock& block, const Batch& batch, Vec<float>& x, Vec<float>& y,
                                          Vec<float>& z) {
    load_rows(block.positions, block.stride, batch, x, y, z);
}

template <typename S, typename Buffers>
PENUMBRA_LANES_INLINE LaneVector<S> reflection_axis(const PoseShadingSetup<S>& setup, const Buffers& buffers,
                                                    const Batch& batch, LaneFrame<S>& f) {
    const Vec<S> &nx = f.nx, &ny = f.ny, &nz = f.nz;
    Vec<S> wx{}, wy{}, wz{};
    load_positions(buffers, batch, wx, wy, wz);
    wx = setup.camera[0] - wx;
    wy = setup.camera[1] - wy;
    wz = setup.camera[2] - wz;
    const Mask<S> position_ok = finite(wx) & finite(wy) & finite(wz);
    f.valid &= position_ok;
    const Mask<S> has_view = normalize_lanes<S>(wx, wy, wz, nx, ny, nz) & position_ok;
    const Vec<S> cosine = nx * wx + ny * wy + nz * wz;
    Vec<S> hx = wx - cosine * nx, hy = wy - cosine * ny, hz = wz - cosine * nz;
    const Mask<S> horizon = (hx * hx + hy * hy + hz * hz > S(1e-24)) & normalize_lanes<S>(hx, hy, hz, nx, ny, nz);
    const Mask<S> behind = cosine < S(0);
    Vec<S> rx = S(2) * cosine * nx - wx, ry = S(2) * cosine * ny - wy, rz = S(2) * cosine * nz - wz;
    rx = behind ? (horizon ? -hx : nx) : rx;
    ry = behind ? (horizon ? -hy : ny) : ry;
    rz = behind ? (horizon ? -hz : nz) : rz;
    normalize_lanes<S>(rx, ry, rz, nx, ny, nz);
    return {has_view ? rx : nx, has_view ? ry : ny, has_view ? rz : nz};
}

// F' = Rz(φ) Ry(θ) with F' e_z = z': columns e1' = (cφ cθ, sφ cθ, −sθ),
// e2' = (−sφ, cφ, 0), e3' = z'; at the poles φ is free (0). M = F'ᵀ F takes
// local (t, b, n) coordinates to F' coordinates.
template <typename S>
struct LaneRotation {
    Vec<S> ct, st, cp, sp;
    Vec<S> m00, m01, m02, m10, m11, m12, m20, m21, m22;
};

template <typename S>
PENUMBRA_LANES_INLINE LaneRotation<S> frame_rotation(const LaneVector<S>& z, const LaneFrame<S>& f) {
    LaneRotation<S> q;
    q.ct = z.z;
    q.st = sqrt_lanes(z.x * z.x + z.y * z.y);
    const Mask<S> pole = !(q.st > S(0));
    const Vec<S> inverse_st = S(1) / (pole ? splat<S>(1) : q.st);
    q.cp = pole ? splat<S>(1) : z.x * inverse_st;
    q.sp = pole ? splat<S>(0) : z.y * inverse_st;
    const Vec<S> e1x = q.cp * q.ct, e1y = q.sp * q.ct, e1z = -q.st;
    const Vec<S> e3x = q.cp * q.st, e3y = q.sp * q.st, e3z = q.ct;
    q.m00 = e1x * f.tx + e1y * f.ty + e1z * f.tz;
    q.m01 = e1x * f.bx + e1y * f.by + e1z * f.bz;
    q.m02 = e1x * f.nx + e1y * f.ny + e1z * f.nz;
    q.m10 = q.cp * f.ty - q.sp * f.tx;
    q.m11 = q.cp * f.by - q.sp * f.bx;
    q.m12 = q.cp * f.ny - q.sp * f.nx;
    q.m20 = e3x * f.tx + e3y * f.ty + e3z * f.tz;
    q.m21 = e3x * f.bx + e3y * f.by + e3z * f.bz;
    q.m22 = e3x * f.nx + e3y * f.ny + e3z * f.nz;
    return q;
}

// The axis of Lambert azimuthal equal-area coordinates (X, Y) about +z
// (visibility/zh_fit.hpp's lambert_to_axis): (s X, s Y, 1 − r²/2) with
// s = sqrt(1 − r²/4), unit by construction; beyond the disc r = 2 the point
// is pulled onto its rim; non-finite coordinates give +z.
template <typename S>
PENUMBRA_LANES_INLINE LaneVector<S> lambert_axis(Vec<S> x, Vec<S> y) {
    Vec<S> r2 = x * x + y * y;
    const Mask<S> usable = finite(r2), outside = usable & (r2 > S(4));
    const Vec<S> pull = S(2) / sqrt_lanes(outside ? r2 : splat<S>(4));
    x = outside ? x * pull : x;
    y = outside ? y * pull : y;
    r2 = outside ? splat<S>(4) : r2;
    const Vec<S> rest = S(1) - S(0.25) * r2;
    const Vec<S> s = sqrt_lanes(rest > S(0) ? rest : splat<S>(0));
    return {usable ? s * x : splat<S>(0), usable ? s * y : splat<S>(0), usable ? S(1) - S(0.5) * r2 : splat<S>(1)};
}

// One lobe of every lane: its local axis (normalized) and bands, zeroed
// where the lobe is unused or the vertex invalid (which it updates: a zero
// axis with zero bands is an unused lobe; anything else that is zero or
// non-finite makes the vertex invalid).
template <typename S>
PENUMBRA_LANES_INLINE LaneVector<S> load_lobe_raw(const PoseBuffers<S>& buffers, const Batch& batch, int lobe,
                                                  int lobes, int order, Vec<S>* band);

PENUMBRA_LANES_INLINE LaneVector<float> load_lobe_raw(const PoseBlock& block, const Batch& batch, int lobe, int,
                                                      int order, Vec<float>* band) {
    const float* rows = block.lobe_params + std::size_t(lobe) * (2 + order) * block.stride;
    for (int l = 0; l < order; ++l) band[l] = load_row(rows + (2 + l) * block.stride, batch);
    return lambert_axis<float>(load_row(rows, batch), load_row(rows + block.stride, batch));
}

template <typename S, typename Buffers>
PENUMBRA_LANES_INLINE LaneVector<S> load_lobe(const Buffers& buffers, const Batch& batch, int lobe, int lobes,
                                              int order, Vec<S>* band, Mask<S>& valid) {
    const LaneVector<S> a = load_lobe_raw(buffers, batch, lobe, lobes, order, band);
    Mask<S> bands_finite = finite(band[0]), bands_zero = band[0] == S(0);
    for (int l = 1; l < order; ++l) {
        bands_finite &= finite(band[l]);
        bands_zero &= band[l] == S(0);
    }
    LaneVector<S> unit = a;
    Mask<S> axis_ok = bands_finite | ~bands_finite;
    // Axes from a block's lobe parameters are unit by construction
    // (lambert_axis): nothing to normalize or check.
    if constexpr (!std::is_same_v<Buffers, PoseBlock>)
        axis_ok = normalize_lanes<S>(unit.x, unit.y, unit.z, S(0), S(0), S(1));
    valid &= bands_finite & (axis_ok | bands_zero);
    const Mask<S> use = axis_ok & bands_finite & valid;
    for (int l = 0; l < order; ++l) band[l] = use ? band[l] : splat<S>(0);
    return unit;
}

// A lobe's axis and bands as stored (PoseBuffers): axes and bands, or
// lobe parameters.
template <typename S>
PENUMBRA_LANES_INLINE LaneVector<S> load_lobe_raw(const PoseBuffers<S>& buffers, const Batch& batch, int lobe,
                                                  int lobes, int order, Vec<S>* band) {
    LaneVector<S> a{};
    if (buffers.lobe_params) {
        for (int k = 0; k < Lanes<S>::count; ++k) {
            const S* p = buffers.lobe_params + (batch.vertex(k) * lobes + lobe) * (2 + order);
            a.x[k] = p[0]; a.y[k] = p[1];
            for (int l = 0; l < order; ++l) band[l][k] = p[2 + l];
        }
        a = lambert_axis<S>(a.x, a.y);
    } else {
        for (int k = 0; k < Lanes<S>::count; ++k) {
            const std::size_t at = batch.vertex(k) * lobes + lobe;
            const S* axis = buffers.lobe_axes + 3 * at;
            const S* g = buffers.lobe_bands + order * at;
            a.x[k] = axis[0]; a.y[k] = axis[1]; a.z[k] = axis[2];
            for (int l = 0; l < order; ++l) band[l][k] = g[l];
        }
    }
    return a;
}

// Phong's visibility output: v_l0 in the normal frame depends on the local
// axis' z only, y_l0 = p̄_l0(z) (the m = 0 Legendre recurrence); adds the
// lobe's share to normal_zonal.
template <typename S>
PENUMBRA_LANES_INLINE void add_normal_zonal(const PoseShadingSetup<S>& setup, int order, const Vec<S>& zn,
                                            const Vec<S>* band, Vec<S>* normal_zonal) {
    Vec<S> before = splat<S>(setup.legendre_diagonal[0]), last = splat<S>(0);
    normal_zonal[0] += setup.zh_scale[0] * band[0] * before;
    if (order > 1) {
        last = setup.legendre_first[0] * zn * before;
        normal_zonal[1] += setup.zh_scale[1] * band[1] * last;
    }
    for (int l = 2; l < order; ++l) {
        const int i = sh_index(l, 0);
        const Vec<S> next = setup.legendre_a[i] * (zn * last - setup.legendre_b[i] * before);
        normal_zonal[l] += setup.zh_scale[l] * band[l] * next;
        before = last;
        last = next;
    }
}

// Steps 2–3: every lobe turned into F' and expanded by Eq. 1 into v (and,
// for Phong's visibility output, into normal_zonal). y and band are scratch.
template <typename S, int kOrder, typename Buffers>
PENUMBRA_LANES_INLINE void lobes_to_sh_lanes(const PoseShadingSetup<S>& setup, const Buffers& buffers,
                                             const Batch& batch, const Plan& plan, const LaneRotation<S>& q,
                                             Mask<S>& valid, Vec<S>* v, Vec<S>* normal_zonal, Vec<S>* y,
                                             Vec<S>* band) {
    const int order = kOrder ? kOrder : plan.order;
    for (int i = 0; i < order * order; ++i) v[i] = splat<S>(0);
    for (int l = 0; l < order; ++l) normal_zonal[l] = splat<S>(0);
    for (int lobe = 0; lobe < plan.lobes; ++lobe) {
        const LaneVector<S> a = load_lobe<S, Buffers>(buffers, batch, lobe, plan.lobes, order, band, valid);
        const Vec<S> x = q.m00 * a.x + q.m01 * a.y + q.m02 * a.z;
        const Vec<S> yy = q.m10 * a.x + q.m11 * a.y + q.m12 * a.z;
        const Vec<S> z = q.m20 * a.x + q.m21 * a.y + q.m22 * a.z;
        Vec<S> scale[kOrder ? kOrder : max_order];
        for (int l = 0; l < order; ++l) scale[l] = setup.zh_scale[l] * band[l];
        accumulate_lobe_lanes<S, kOrder>(setup, x, yy, z, scale, v);
        if (plan.phong_visibility) add_normal_zonal<S>(setup, order, a.z, band, normal_zonal);
    }
}

// Step 4: u = T v, block by block over m.
template <typename S, int kOrder>
PENUMBRA_LANES_INLINE void apply_operator_lanes(const PoseShadingSetup<S>& setup, int order_runtime, const Vec<S>* v,
                                                Vec<S>* u) {
    const int order = kOrder ? kOrder : order_runtime;
    for (int m = -(order - 1); m < order; ++m) {
        const int a = std::abs(m), size = order - a;
        const S* block = setup.blocks.data() + setup.block_offset[a];
        for (int l = 0; l < size; ++l) {
            Vec<S> sum = block[l * size] * v[sh_index(a, m)];
            for (int lp = 1; lp < size; ++lp) sum += block[l * size + lp] * v[sh_index(lp + a, m)];
            u[sh_index(l + a, m)] = sum;
        }
    }
}

// Step 5: u back to world, D(F') = Dz(φ) Xᵀ Dz(θ) X, dotted with the
// lighting; translucency adds the back lobe about −n (folded into
// setup.back: needs y(n) in world). u and y are overwritten.
template <typename S, int kOrder>
PENUMBRA_LANES_INLINE void world_rgb_lanes(const PoseShadingSetup<S>& setup, const Plan& plan,
                                           const LaneRotation<S>& q, const LaneFrame<S>& f, Vec<S>* u, Vec<S>* y,
                                           Vec<S>* rgb) {
    const int order = kOrder ? kOrder : plan.order;
    const int coefficients = order * order;
    quarter_turn_lanes<S, kOrder>(order, setup.x_columns, setup.x_values, u, y);
    rotate_z_lanes<S, kOrder>(order, q.ct, q.st, y);
    quarter_turn_lanes<S, kOrder>(order, setup.xt_columns, setup.xt_values, y, u);
    rotate_z_lanes<S, kOrder>(order, q.cp, q.sp, u);
    rgb[0] = rgb[1] = rgb[2] = splat<S>(0);
    for (int i = 0; i < coefficients; ++i)
        for (int c = 0; c < 3; ++c) rgb[c] += setup.lighting[i][c] * u[i];
    if (plan.translucent) {
        eval_lanes<S, kOrder>(setup, f.nx, f.ny, f.nz, y);
        for (int i = 0; i < coefficients; ++i)
            for (int c = 0; c < 3; ++c) rgb[c] += setup.back[i][c] * y[i];
    }
}

// The outputs of the batch's real vertices (0 for invalid ones, counted).
template <typename S>
PENUMBRA_LANES_INLINE void store_batch(const PoseBuffers<S>& buffers, const Batch& batch, Mask<S> valid,
                                       const Vec<S>* rgb, const Vec<S>& visibility, std::size_t& invalid_count) {
    for (int k = 0; k < batch.count; ++k) {
        const std::size_t vertex = batch.start + k;
        const bool ok = valid[k] != 0;
        invalid_count += ok ? 0 : 1;
        for (int c = 0; c < 3; ++c) buffers.rgb[3 * vertex + c] = ok ? rgb[c][k] : S(0);
        if (buffers.visibility) buffers.visibility[vertex] = ok ? visibility[k] : S(0);
    }
}

// A block's rows: whole lanes (past vertex_count too, discarded there).
PENUMBRA_LANES_INLINE void store_batch(const PoseBlock& block, const Batch& batch, Mask<float> valid,
                                       const Vec<float>* rgb, const Vec<float>& visibility,
                                       std::size_t& invalid_count) {
    for (int k = 0; k < batch.count; ++k) invalid_count += valid[k] ? 0 : 1;
    const Vec<float> zero{};
    for (int c = 0; c < 3; ++c) {
        const Vec<float> out = valid ? rgb[c] : zero;
        std::memcpy(block.rgb + c * block.stride + batch.start, &out, sizeof out);
    }
    if (block.visibility) {
        const Vec<float> out = valid ? visibility : zero;
        std::memcpy(block.visibility + batch.start, &out, sizeof out);
    }
}

// Shades vertices [begin, end) in S, the buffers' precision.
template <typename S, int kOrder, typename Buffers>
void shade_batches(const PoseShadingSetup<S>& setup, const Buffers& buffers, std::size_t begin, std::size_t end,
                   std::size_t& invalid_count) {
    constexpr int kBands = kOrder ? kOrder : max_order;
    constexpr int kLanes = Lanes<S>::count;
    const bool phong = setup.model == ShadingModel::phong;
    const Plan plan{kOrder ? kOrder : setup.order, setup.lobes, phong, setup.model == ShadingModel::translucent,
                    phong && setup.want_visibility};

    Vec<S> v[kBands * kBands], y[kBands * kBands], u[kBands * kBands];
    Vec<S> normal_zonal[kBands];  // phong visibility output: v_l0 in the normal frame
    Vec<S> band[kBands] = {};

    for (std::size_t start = begin; start < end; start += kLanes) {
        const Batch batch{start, int(std::min<std::size_t>(kLanes, end - start))};
        LaneFrame<S> frame = load_frames<S, Buffers>(buffers, batch);
        // z' = n, or for Phong the reflection axis r.
        const LaneVector<S> axis = plan.phong ? reflection_axis<S, Buffers>(setup, buffers, batch, frame)
                                              : LaneVector<S>{frame.nx, frame.ny, frame.nz};
        const LaneRotation<S> rotation = frame_rotation<S>(axis, frame);
        lobes_to_sh_lanes<S, kOrder, Buffers>(setup, buffers, batch, plan, rotation, frame.valid, v, normal_zonal, y,
                                              band);
        apply_operator_lanes<S, kOrder>(setup, plan.order, v, u);
        Vec<S> rgb[3];
        world_rgb_lanes<S, kOrder>(setup, plan, rotation, frame, u, y, rgb);
        Vec<S> visibility = splat<S>(0);
        if (buffers.visibility)
            for (int l = 0; l < plan.order; ++l)
                visibility += setup.ao_weight[l] * (plan.phong ? normal_zonal[l] : v[sh_index(l, 0)]);
        store_batch(buffers, batch, frame.valid, rgb, visibility, invalid_count);
    }
}

template <typename S, int kOrder>
void shade_range(const PoseShadingSetup<S>& setup, const PoseBuffers<S>& buffers, std::size_t begin,
                 std::size_t end, std::size_t& invalid_count) {
    shade_batches<S, kOrder, PoseBuffers<S>>(setup, buffers, begin, end, invalid_count);
}

template <int kOrder>
void shade_block(const PoseShadingSetup<float>& setup, const PoseBlock& block, std::size_t& invalid_count) {
    shade_batches<float, kOrder, PoseBlock>(setup, block, 0, block.vertex_count, invalid_count);
}

template <typename S>
RangeFunction<S> range_function(int order) {
    switch (order) {
        case 1: return &shade_range<S, 1>;
        case 2: return &shade_range<S, 2>;
        case 3: return &shade_range<S, 3>;
        case 4: return &shade_range<S, 4>;
        case 5: return &shade_range<S, 5>;
        case 6: return &shade_range<S, 6>;
        case 7: return &shade_range<S, 7>;
        case 8: return &shade_range<S, 8>;
        default: return &shade_range<S, 0>;
    }
}

BlockFunction block_function(int order) {
    switch (order) {
        case 1: return &shade_block<1>;
        case 2: return &shade_block<2>;
        case 3: return &shade_block<3>;
        case 4: return &shade_block<4>;
        case 5: return &shade_block<5>;
        case 6: return &shade_block<6>;
        case 7: return &shade_block<7>;
        case 8: return &shade_block<8>;
        default: return &shade_block<0>;
    }
}

RangeFunction<float> range_function_float(int order) { return range_function<float>(order); }
RangeFunction<double> range_function_double(int order) { return range_function<double>(order); }
int lanes() { return Lanes<double>::count; }

}  // namespace penumbra::sh::detail::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace penumbra::sh::detail {

HWY_EXPORT(range_function_float);
RangeFunction<float> range_function_float(int order) { return HWY_DYNAMIC_DISPATCH(range_function_float)(order); }

HWY_EXPORT(range_function_double);
RangeFunction<double> range_function_double(int order) { return HWY_DYNAMIC_DISPATCH(range_function_double)(order); }

HWY_EXPORT(block_function);
BlockFunction block_function(int order) { return HWY_DYNAMIC_DISPATCH(block_function)(order); }

HWY_EXPORT(lanes);
int simd_lanes() { return HWY_DYNAMIC_DISPATCH(lanes)(); }

}  // namespace penumbra::sh::detail
#endif  // HWY_ONCE
