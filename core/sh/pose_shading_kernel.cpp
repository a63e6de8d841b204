// The hot loop of the pose shader (sh/pose_shading.hpp), compiled once per
// SIMD target by Highway's foreach_target (SSE4, AVX2, AVX-512, and EMU128 as
// the one-lane scalar reference) and chosen at run time by its dynamic
// dispatch, so a portable (x86-64-v2) build still runs AVX2/AVX-512 code
// where the CPU has it.
//
// Layout: vertices go in batches of kLanes, one SIMD register of doubles for
// the target (1 for the scalar reference, 2 with SSE4, 4 with AVX2, 8 with
// AVX-512). Every per-vertex quantity is such a lane vector (GCC/Clang
// vector extensions, which Highway's per-target `#pragma GCC target` turns
// into that target's instructions), so every step is the same straight-line
// arithmetic on all lanes with constants (T, X, lighting) shared by the
// batch, and validity is a lane mask instead of a branch.
// All arithmetic is double. The order is a template parameter for orders 1–8
// (fully unrolled) and a runtime value above.

// Every target at least as good as the baseline, plus EMU128 for the scalar
// reference; SSSE3 is below this build's x86-64-v2 baseline.
#ifndef HWY_COMPILE_ALL_ATTAINABLE
#define HWY_COMPILE_ALL_ATTAINABLE
#endif
#ifndef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS HWY_SSSE3
#endif
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "sh/pose_shading_kernel.cpp"
#include <hwy/foreach_target.h>  // re-includes this file once per target
#include <hwy/highway.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "sh/basis.hpp"
#include "sh/pose_shading_setup.hpp"

HWY_BEFORE_NAMESPACE();
namespace penumbra::sh::detail::HWY_NAMESPACE {

// One lane vector = one SIMD register of doubles for the target being
// compiled: wider vectors are split by the compiler into pieces that go
// through memory, which measured 1.6x slower (docs/sh-engine.md). EMU128 (no
// SIMD instructions) gets one lane: the scalar reference the SIMD targets are
// tested and benchmarked against.
#if HWY_TARGET == HWY_EMU128 || HWY_TARGET == HWY_SCALAR
constexpr int kLanes = 1;
#else
constexpr int kLanes = HWY_LANES(double);
#endif

typedef double VecD __attribute__((vector_size(kLanes * sizeof(double))));
typedef long long MaskD __attribute__((vector_size(kLanes * sizeof(double))));

inline VecD splat(double value) {
    VecD v{};
    for (int k = 0; k < kLanes; ++k) v[k] = value;
    return v;
}

inline VecD sqrt_lanes(const VecD& x) {
    VecD r{};
    for (int k = 0; k < kLanes; ++k) r[k] = std::sqrt(x[k]);
    return r;
}

inline MaskD finite(const VecD& x) { return x - x == 0.0; }  // false for NaN and ±inf

// (x, y, z) ← unit vector in lanes where it is finite and its squared length
// lies in (1e-300, inf) (lengths between ~1e-150 and ~1e154; anything else
// counts as zero or non-finite); returns that mask and sets (x, y, z) to the
// fallback in the other lanes.
inline MaskD normalize_lanes(VecD& x, VecD& y, VecD& z, double fx, double fy, double fz) {
    const VecD squared = x * x + y * y + z * z;
    const MaskD ok = finite(squared) & (squared > 1e-300);
    const VecD inverse_length = 1.0 / sqrt_lanes(ok ? squared : splat(1.0));
    x = ok ? x * inverse_length : splat(fx);
    y = ok ? y * inverse_length : splat(fy);
    z = ok ? z * inverse_length : splat(fz);
    return ok;
}

// Same with per-lane fallbacks.
inline MaskD normalize_lanes(VecD& x, VecD& y, VecD& z, const VecD& fx, const VecD& fy, const VecD& fz) {
    const VecD squared = x * x + y * y + z * z;
    const MaskD ok = finite(squared) & (squared > 1e-300);
    const VecD inverse_length = 1.0 / sqrt_lanes(ok ? squared : splat(1.0));
    x = ok ? x * inverse_length : fx;
    y = ok ? y * inverse_length : fy;
    z = ok ? z * inverse_length : fz;
    return ok;
}

// y_i(x, y, z) for unit directions in every lane: the Cartesian recurrence of
// sh/basis.cpp (Legendre in z by sh/legendre.hpp, then (x + iy)^m).
template <int kOrder>
inline void eval_lanes(const PoseShadingSetup& setup, const VecD& x, const VecD& y, const VecD& z,
                       VecD* out) {
    const int order = kOrder ? kOrder : setup.order;
    const LegendreRecurrence& legendre = setup.legendre;
    for (int m = 0; m < order; ++m) {
        out[sh_index(m, m)] = splat(legendre.diagonal[m]);
        if (m + 1 >= order) break;
        out[sh_index(m + 1, m)] = legendre.first[m] * z * legendre.diagonal[m];
        for (int l = m + 2; l < order; ++l) {
            const int i = sh_index(l, m);
            out[i] = legendre.a[i] * (z * out[sh_index(l - 1, m)] - legendre.b[i] * out[sh_index(l - 2, m)]);
        }
    }
    // C_m + i S_m = (x + iy)^m.
    VecD c = splat(1.0), s = splat(0.0);
    const double sqrt2 = std::numbers::sqrt2;
    for (int m = 1; m < order; ++m) {
        const VecD c_next = x * c - y * s;
        s = x * s + y * c;
        c = c_next;
        const VecD sc = sqrt2 * c, ss = sqrt2 * s;
        for (int l = m; l < order; ++l) {
            const VecD p = out[sh_index(l, m)];
            out[sh_index(l, -m)] = p * ss;
            out[sh_index(l, m)] = p * sc;
        }
    }
}

// In place: coefficients of f turned by Rz(α) (g(ω) = f(Rz(α)ᵀ ω)), per lane
// with (cos α, sin α) = (c, s): (p, q) = (w_lm, w_l,−m) →
// (p cos mα − q sin mα, p sin mα + q cos mα).
template <int kOrder>
inline void rotate_z_lanes(int order_runtime, const VecD& c, const VecD& s, VecD* w) {
    const int order = kOrder ? kOrder : order_runtime;
    VecD cm = c, sm = s;
    for (int m = 1; m < order; ++m) {
        if (m > 1) {
            const VecD c_next = cm * c - sm * s;
            sm = sm * c + cm * s;
            cm = c_next;
        }
        for (int l = m; l < order; ++l) {
            const VecD p = w[sh_index(l, m)], q = w[sh_index(l, -m)];
            w[sh_index(l, m)] = p * cm - q * sm;
            w[sh_index(l, -m)] = p * sm + q * cm;
        }
    }
}

// out = X in, X given by its non-zero entries (24 of 84 at order 4).
template <int kOrder>
inline void quarter_turn_lanes(int order_runtime, const std::vector<int>& rows, const std::vector<int>& columns,
                               const std::vector<double>& values, const VecD* in, VecD* out) {
    const int order = kOrder ? kOrder : order_runtime;
    for (int i = 0; i < order * order; ++i) out[i] = splat(0.0);
    const std::size_t count = values.size();
    for (std::size_t e = 0; e < count; ++e) out[rows[e]] += values[e] * in[columns[e]];
}

// The steps of shading one batch of kLanes vertices, in the order
// shade_range calls them (paper §4.3 steps 2–5, docs/sh-engine.md). Each is
// forced inline so the batch stays one straight-line block in registers.
#define PENUMBRA_LANES_INLINE [[gnu::always_inline]] inline

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
struct LaneFrame {
    VecD nx, ny, nz, tx, ty, tz, bx, by, bz;
    MaskD valid;
};

// n = normalize(normal), t = the tangent Gram–Schmidt'ed against n, b = n × t
// (header); invalid lanes get (t, b, n) = (x, y, z).
template <typename Real>
PENUMBRA_LANES_INLINE LaneFrame load_frames(const PoseBuffers<Real>& buffers, const Batch& batch) {
    LaneFrame f{};
    for (int k = 0; k < kLanes; ++k) {
        const std::size_t vertex = batch.vertex(k);
        const Real* np = buffers.normals + 3 * vertex;
        const Real* tp = buffers.tangents + 3 * vertex;
        f.nx[k] = double(np[0]); f.ny[k] = double(np[1]); f.nz[k] = double(np[2]);
        f.tx[k] = double(tp[0]); f.ty[k] = double(tp[1]); f.tz[k] = double(tp[2]);
    }
    f.valid = normalize_lanes(f.nx, f.ny, f.nz, 0.0, 0.0, 1.0);
    // Gram–Schmidt; a tangent within 1e-6 rad of n leaves nothing usable.
    f.valid &= normalize_lanes(f.tx, f.ty, f.tz, 1.0, 0.0, 0.0);
    const VecD along = f.tx * f.nx + f.ty * f.ny + f.tz * f.nz;
    f.tx -= along * f.nx; f.ty -= along * f.ny; f.tz -= along * f.nz;
    f.valid &= f.tx * f.tx + f.ty * f.ty + f.tz * f.tz > 1e-12;
    f.valid &= normalize_lanes(f.tx, f.ty, f.tz, 1.0, 0.0, 0.0);
    const MaskD valid = f.valid;
    f.nx = valid ? f.nx : splat(0.0); f.ny = valid ? f.ny : splat(0.0); f.nz = valid ? f.nz : splat(1.0);
    f.tx = valid ? f.tx : splat(1.0); f.ty = valid ? f.ty : splat(0.0); f.tz = valid ? f.tz : splat(0.0);
    f.bx = f.ny * f.tz - f.nz * f.ty; f.by = f.nz * f.tx - f.nx * f.tz; f.bz = f.nx * f.ty - f.ny * f.tx;
    return f;
}

struct LaneVector {
    VecD x, y, z;
};

// Phong's axis r = 2(n·w) n − w, w = normalize(camera − position), clamped
// to the horizon when n·w < 0; r = n where w or the clamp is undefined. A
// non-finite position makes the lane invalid.
template <typename Real>
PENUMBRA_LANES_INLINE LaneVector reflection_axis(const PoseShadingSetup& setup, const PoseBuffers<Real>& buffers,
                                                 const Batch& batch, LaneFrame& f) {
    const VecD &nx = f.nx, &ny = f.ny, &nz = f.nz;
    VecD wx{}, wy{}, wz{};
    for (int k = 0; k < kLanes; ++k) {
        const Real* pp = buffers.positions + 3 * batch.vertex(k);
        wx[k] = setup.camera.x() - double(pp[0]);
        wy[k] = setup.camera.y() - double(pp[1]);
        wz[k] = setup.camera.z() - double(pp[2]);
    }
    const MaskD position_ok = finite(wx) & finite(wy) & finite(wz);
    f.valid &= position_ok;
    const MaskD has_view = normalize_lanes(wx, wy, wz, nx, ny, nz) & position_ok;
    const VecD cosine = nx * wx + ny * wy + nz * wz;
    VecD hx = wx - cosine * nx, hy = wy - cosine * ny, hz = wz - cosine * nz;
    const MaskD horizon = (hx * hx + hy * hy + hz * hz > 1e-24) & normalize_lanes(hx, hy, hz, nx, ny, nz);
    const MaskD behind = cosine < 0.0;
    VecD rx = 2.0 * cosine * nx - wx, ry = 2.0 * cosine * ny - wy, rz = 2.0 * cosine * nz - wz;
    rx = behind ? (horizon ? -hx : nx) : rx;
    ry = behind ? (horizon ? -hy : ny) : ry;
    rz = behind ? (horizon ? -hz : nz) : rz;
    normalize_lanes(rx, ry, rz, nx, ny, nz);
    return {has_view ? rx : nx, has_view ? ry : ny, has_view ? rz : nz};
}

// F' = Rz(φ) Ry(θ) with F' e_z = z': columns e1' = (cφ cθ, sφ cθ, −sθ),
// e2' = (−sφ, cφ, 0), e3' = z'; at the poles φ is free (0). M = F'ᵀ F takes
// local (t, b, n) coordinates to F' coordinates.
struct LaneRotation {
    VecD ct, st, cp, sp;
    VecD m00, m01, m02, m10, m11, m12, m20, m21, m22;
};

PENUMBRA_LANES_INLINE LaneRotation frame_rotation(const LaneVector& z, const LaneFrame& f) {
    LaneRotation q;
    q.ct = z.z;
    q.st = sqrt_lanes(z.x * z.x + z.y * z.y);
    const MaskD pole = !(q.st > 0.0);
    const VecD inverse_st = 1.0 / (pole ? splat(1.0) : q.st);
    q.cp = pole ? splat(1.0) : z.x * inverse_st;
    q.sp = pole ? splat(0.0) : z.y * inverse_st;
    const VecD e1x = q.cp * q.ct, e1y = q.sp * q.ct, e1z = -q.st;
    const VecD e3x = q.cp * q.st, e3y = q.sp * q.st, e3z = q.ct;
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

// One lobe of every lane: its local axis (normalized) and bands, zeroed
// where the lobe is unused or the vertex invalid (which it updates: a zero
// axis with zero bands is an unused lobe; anything else that is zero or
// non-finite makes the vertex invalid).
template <typename Real>
PENUMBRA_LANES_INLINE LaneVector load_lobe(const PoseBuffers<Real>& buffers, const Batch& batch, int lobe, int lobes,
                                           int order, VecD* band, MaskD& valid) {
    LaneVector a{};
    for (int k = 0; k < kLanes; ++k) {
        const std::size_t at = batch.vertex(k) * lobes + lobe;
        const Real* axis = buffers.lobe_axes + 3 * at;
        const Real* g = buffers.lobe_bands + order * at;
        a.x[k] = double(axis[0]); a.y[k] = double(axis[1]); a.z[k] = double(axis[2]);
        for (int l = 0; l < order; ++l) band[l][k] = double(g[l]);
    }
    MaskD bands_finite = finite(band[0]), bands_zero = band[0] == 0.0;
    for (int l = 1; l < order; ++l) {
        bands_finite &= finite(band[l]);
        bands_zero &= band[l] == 0.0;
    }
    const MaskD axis_ok = normalize_lanes(a.x, a.y, a.z, 0.0, 0.0, 1.0);
    valid &= bands_finite & (axis_ok | bands_zero);
    const MaskD use = axis_ok & bands_finite & valid;
    for (int l = 0; l < order; ++l) band[l] = use ? band[l] : splat(0.0);
    return a;
}

// Phong's visibility output: v_l0 in the normal frame depends on the local
// axis' z only, y_l0 = p̄_l0(z) (the m = 0 Legendre recurrence); adds the
// lobe's share to normal_zonal.
PENUMBRA_LANES_INLINE void add_normal_zonal(const PoseShadingSetup& setup, int order, const VecD& zn,
                                            const VecD* band, VecD* normal_zonal) {
    const LegendreRecurrence& legendre = setup.legendre;
    VecD before = splat(legendre.diagonal[0]), last = splat(0.0);
    normal_zonal[0] += setup.zh_scale[0] * band[0] * before;
    if (order > 1) {
        last = legendre.first[0] * zn * before;
        normal_zonal[1] += setup.zh_scale[1] * band[1] * last;
    }
    for (int l = 2; l < order; ++l) {
        const int i = sh_index(l, 0);
        const VecD next = legendre.a[i] * (zn * last - legendre.b[i] * before);
        normal_zonal[l] += setup.zh_scale[l] * band[l] * next;
        before = last;
        last = next;
    }
}

// Steps 2–3: every lobe turned into F' and expanded by Eq. 1 into v (and,
// for Phong's visibility output, into normal_zonal). y and band are scratch.
template <typename Real, int kOrder>
PENUMBRA_LANES_INLINE void lobes_to_sh_lanes(const PoseShadingSetup& setup, const PoseBuffers<Real>& buffers,
                                             const Batch& batch, const Plan& plan, const LaneRotation& q,
                                             MaskD& valid, VecD* v, VecD* normal_zonal, VecD* y, VecD* band) {
    const int order = kOrder ? kOrder : plan.order;
    for (int i = 0; i < order * order; ++i) v[i] = splat(0.0);
    for (int l = 0; l < order; ++l) normal_zonal[l] = splat(0.0);
    for (int lobe = 0; lobe < plan.lobes; ++lobe) {
        const LaneVector a = load_lobe(buffers, batch, lobe, plan.lobes, order, band, valid);
        const VecD x = q.m00 * a.x + q.m01 * a.y + q.m02 * a.z;
        const VecD yy = q.m10 * a.x + q.m11 * a.y + q.m12 * a.z;
        const VecD z = q.m20 * a.x + q.m21 * a.y + q.m22 * a.z;
        eval_lanes<kOrder>(setup, x, yy, z, y);
        for (int l = 0; l < order; ++l) {
            const VecD scale = setup.zh_scale[l] * band[l];
            for (int m = -l; m <= l; ++m) v[sh_index(l, m)] += scale * y[sh_index(l, m)];
        }
        if (plan.phong_visibility) add_normal_zonal(setup, order, a.z, band, normal_zonal);
    }
}

// Step 4: u = T v, block by block over m.
template <int kOrder>
PENUMBRA_LANES_INLINE void apply_operator_lanes(const PoseShadingSetup& setup, int order_runtime, const VecD* v,
                                                VecD* u) {
    const int order = kOrder ? kOrder : order_runtime;
    for (int m = -(order - 1); m < order; ++m) {
        const int a = std::abs(m), size = order - a;
        const double* block = setup.blocks.data() + setup.block_offset[a];
        for (int l = 0; l < size; ++l) {
            VecD sum = block[l * size] * v[sh_index(a, m)];
            for (int lp = 1; lp < size; ++lp) sum += block[l * size + lp] * v[sh_index(lp + a, m)];
            u[sh_index(l + a, m)] = sum;
        }
    }
}

// Step 5: u back to world, D(F') = Dz(φ) Xᵀ Dz(θ) X, dotted with the
// lighting; translucency adds the back lobe about −n (folded into
// setup.back: needs y(n) in world). u and y are overwritten.
template <int kOrder>
PENUMBRA_LANES_INLINE void world_rgb_lanes(const PoseShadingSetup& setup, const Plan& plan, const LaneRotation& q,
                                           const LaneFrame& f, VecD* u, VecD* y, VecD* rgb) {
    const int order = kOrder ? kOrder : plan.order;
    const int coefficients = order * order;
    quarter_turn_lanes<kOrder>(order, setup.x_rows, setup.x_columns, setup.x_values, u, y);
    rotate_z_lanes<kOrder>(order, q.ct, q.st, y);
    quarter_turn_lanes<kOrder>(order, setup.xt_rows, setup.xt_columns, setup.xt_values, y, u);
    rotate_z_lanes<kOrder>(order, q.cp, q.sp, u);
    rgb[0] = rgb[1] = rgb[2] = splat(0.0);
    for (int i = 0; i < coefficients; ++i)
        for (int c = 0; c < 3; ++c) rgb[c] += setup.lighting[i][c] * u[i];
    if (plan.translucent) {
        eval_lanes<kOrder>(setup, f.nx, f.ny, f.nz, y);
        for (int i = 0; i < coefficients; ++i)
            for (int c = 0; c < 3; ++c) rgb[c] += setup.back[i][c] * y[i];
    }
}

// The outputs of the batch's real vertices (0 for invalid ones, counted).
template <typename Real>
PENUMBRA_LANES_INLINE void store_batch(const PoseBuffers<Real>& buffers, const Batch& batch, MaskD valid,
                                       const VecD* rgb, const VecD& visibility, std::size_t& invalid_count) {
    for (int k = 0; k < batch.count; ++k) {
        const std::size_t vertex = batch.start + k;
        const bool ok = valid[k] != 0;
        invalid_count += ok ? 0 : 1;
        for (int c = 0; c < 3; ++c) buffers.rgb[3 * vertex + c] = ok ? static_cast<Real>(rgb[c][k]) : Real(0);
        if (buffers.visibility) buffers.visibility[vertex] = ok ? static_cast<Real>(visibility[k]) : Real(0);
    }
}

// Shades vertices [begin, end).
template <typename Real, int kOrder>
void shade_range(const PoseShadingSetup& setup, const PoseBuffers<Real>& buffers, std::size_t begin,
                 std::size_t end, std::size_t& invalid_count) {
    constexpr int kBands = kOrder ? kOrder : max_order;
    const bool phong = setup.model == ShadingModel::phong;
    const Plan plan{kOrder ? kOrder : setup.order, setup.lobes, phong, setup.model == ShadingModel::translucent,
                    phong && setup.want_visibility};

    VecD v[kBands * kBands], y[kBands * kBands], u[kBands * kBands];
    VecD normal_zonal[kBands];  // phong visibility output: v_l0 in the normal frame
    VecD band[kBands] = {};

    for (std::size_t start = begin; start < end; start += kLanes) {
        const Batch batch{start, int(std::min<std::size_t>(kLanes, end - start))};
        LaneFrame frame = load_frames(buffers, batch);
        // z' = n, or for Phong the reflection axis r.
        const LaneVector axis = plan.phong ? reflection_axis(setup, buffers, batch, frame)
                                           : LaneVector{frame.nx, frame.ny, frame.nz};
        const LaneRotation rotation = frame_rotation(axis, frame);
        lobes_to_sh_lanes<Real, kOrder>(setup, buffers, batch, plan, rotation, frame.valid, v, normal_zonal, y, band);
        apply_operator_lanes<kOrder>(setup, plan.order, v, u);
        VecD rgb[3];
        world_rgb_lanes<kOrder>(setup, plan, rotation, frame, u, y, rgb);
        VecD visibility = splat(0.0);
        if (buffers.visibility)
            for (int l = 0; l < plan.order; ++l)
                visibility += setup.ao_weight[l] * (plan.phong ? normal_zonal[l] : v[sh_index(l, 0)]);
        store_batch(buffers, batch, frame.valid, rgb, visibility, invalid_count);
    }
}

#undef PENUMBRA_LANES_INLINE

template <typename Real>
RangeFunction<Real> range_function(int order) {
    switch (order) {
        case 1: return &shade_range<Real, 1>;
        case 2: return &shade_range<Real, 2>;
        case 3: return &shade_range<Real, 3>;
        case 4: return &shade_range<Real, 4>;
        case 5: return &shade_range<Real, 5>;
        case 6: return &shade_range<Real, 6>;
        case 7: return &shade_range<Real, 7>;
        case 8: return &shade_range<Real, 8>;
        default: return &shade_range<Real, 0>;
    }
}

RangeFunction<float> range_function_float(int order) { return range_function<float>(order); }
RangeFunction<double> range_function_double(int order) { return range_function<double>(order); }
int lanes() { return kLanes; }

}  // namespace penumbra::sh::detail::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace penumbra::sh::detail {

HWY_EXPORT(range_function_float);
HWY_EXPORT(range_function_double);
HWY_EXPORT(lanes);

RangeFunction<float> range_function_float(int order) { return HWY_DYNAMIC_DISPATCH(range_function_float)(order); }
RangeFunction<double> range_function_double(int order) { return HWY_DYNAMIC_DISPATCH(range_function_double)(order); }
int simd_lanes() { return HWY_DYNAMIC_DISPATCH(lanes)(); }

}  // namespace penumbra::sh::detail

namespace penumbra::sh {

// HWY_TARGETS of this file (it compiles EMU128 too): the dispatch table's.
std::vector<std::string> simd_targets() {
    std::vector<std::string> names;
    for (const std::int64_t target : hwy::SupportedAndGeneratedTargets()) names.push_back(hwy::TargetName(target));
    return names;
}

std::string simd_target() { return simd_targets().front(); }

void force_simd_target(const std::string& name) {
    hwy::SetSupportedTargetsForTest(0);  // the CPU's own list, and the dispatch chooses again
    if (name.empty()) return;
    for (const std::int64_t target : hwy::SupportedAndGeneratedTargets())
        if (name == hwy::TargetName(target)) {
            hwy::SetSupportedTargetsForTest(target);
            return;
        }
    std::string known;
    for (const std::string& n : simd_targets()) known += (known.empty() ? "" : ", ") + n;
    throw ArgumentError("SIMD target '" + name + "' is not compiled in or not supported by this CPU (have: " + known + ")");
}

}  // namespace penumbra::sh
#endif  // HWY_ONCE
