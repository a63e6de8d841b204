// The per-vertex and per-face SIMD loops (header: what they compute). Same scheme as
// sh/pose_shading_kernel.cpp: Highway's foreach_target compiles this file
// once per SIMD target, each copy in its own namespace under that target's
// `#pragma GCC target`; lane vectors are GCC/Clang vector extensions of one
// register of floats; HWY_DYNAMIC_DISPATCH runs the best copy for the CPU.
// Compiled with -ffp-contract=off (Blender's face normals bit for bit) and
// -fno-math-errno (a vector square root is one instruction).

#include "common/simd_compiled_targets.hpp"  // before any Highway header
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "visibility/vertex_kernels.cpp"
#include <hwy/foreach_target.h>  // re-includes this file once per target
#include <hwy/highway.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>

#include "common/simd_lanes-inl.h"
#include "visibility/vertex_kernels.hpp"

HWY_BEFORE_NAMESPACE();
namespace penumbra::visibility::detail::HWY_NAMESPACE {

using namespace simd::HWY_NAMESPACE;

struct Lanes3 {
    VecF x, y, z;
};

// Lanes filled one by one go through memory: written lane by lane, read as
// whole vectors (an insert per lane compiled to a chain of masked
// broadcasts, each waiting on the last), and the other way for results read
// lane by lane.
struct Staging3 {
    alignas(64) float x[kFloatLanes], y[kFloatLanes], z[kFloatLanes];
    void set(int k, const float* p) {
        x[k] = p[0];
        y[k] = p[1];
        z[k] = p[2];
    }
    Lanes3 load() const {
        Lanes3 v;
        std::memcpy(&v.x, x, sizeof x);
        std::memcpy(&v.y, y, sizeof y);
        std::memcpy(&v.z, z, sizeof z);
        return v;
    }
    void store(const Lanes3& v) {
        std::memcpy(x, &v.x, sizeof x);
        std::memcpy(y, &v.y, sizeof y);
        std::memcpy(z, &v.z, sizeof z);
    }
};

PENUMBRA_LANES_INLINE Lanes3 minus(const Lanes3& a, const Lanes3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }

typedef float Quad __attribute__((vector_size(4 * sizeof(float))));

PENUMBRA_LANES_INLINE Quad load_quad(const float* p) {
    Quad q;
    std::memcpy(&q, p, sizeof q);
    return q;
}

// Blender's math::dot, left to right.
PENUMBRA_LANES_INLINE VecF dot(const Lanes3& a, const Lanes3& b) {
    VecF r = a.x * b.x;
    r += a.y * b.y;
    r += a.z * b.z;
    return r;
}

// Blender's math::normalize: divide by the length; (nearly) zero or NaN → 0.
PENUMBRA_LANES_INLINE Lanes3 normalized(const Lanes3& v) {
    const VecF squared = dot(v, v);
    const MaskF ok = squared > 1.0e-35f;
    const VecF length = sqrt_lanes(ok ? squared : splat(1.0f));
    return {ok ? v.x / length : splat(0.0f), ok ? v.y / length : splat(0.0f), ok ? v.z / length : splat(0.0f)};
}

// Blender's math::safe_acos_approx (vertex_normals.cpp has the scalar one).
PENUMBRA_LANES_INLINE VecF safe_acos_approx(const VecF& x) {
    const VecF f = x < 0.0f ? -x : x;
    const VecF m = f < 1.0f ? 1.0f - (1.0f - f) : splat(1.0f);
    const VecF a = sqrt_lanes(1.0f - m) * (1.5707963267f + m * (-0.213300989f + m * (0.077980478f + m * -0.02164095f)));
    return x < 0.0f ? float(std::numbers::pi) - a : a;
}

// Position of corner c of each lane's face (the lane's first corner at
// first[k]).
PENUMBRA_LANES_INLINE Lanes3 corner_positions(const float* positions, const std::uint32_t* corner_vertex,
                                              const std::uint32_t* first, int c) {
    Staging3 p;
    for (int k = 0; k < kFloatLanes; ++k) p.set(k, positions + 3 * std::size_t(corner_vertex[first[k] + c]));
    return p.load();
}

// `lanes` ≤ kFloatLanes faces of Size corners each, one per lane (a short batch
// repeats its last face); vertex_normals.hpp's rule, the same operations in
// the same order as face_single.
template <int Size>
void face_batch(const std::uint32_t* face_start, const std::uint32_t* corner_vertex, const float* positions,
                const std::uint32_t* faces, int lanes, float* face_normals, float* corner_angles) {
    std::uint32_t first[kFloatLanes];
    for (int k = 0; k < kFloatLanes; ++k) first[k] = face_start[faces[std::min(k, lanes - 1)]];
    Lanes3 p[Size];
    for (int c = 0; c < Size; ++c) p[c] = corner_positions(positions, corner_vertex, first, c);
    // Newell's method from the last corner round.
    Lanes3 n{splat(0.0f), splat(0.0f), splat(0.0f)};
    for (int c = 0, previous = Size - 1; c < Size; previous = c++) {
        n.x += (p[previous].y - p[c].y) * (p[previous].z + p[c].z);
        n.y += (p[previous].z - p[c].z) * (p[previous].x + p[c].x);
        n.z += (p[previous].x - p[c].x) * (p[previous].y + p[c].y);
    }
    // Edge c runs from corner c to c + 1; corner c's angle is between
    // −edge c−1 and edge c.
    Lanes3 edge[Size];
    for (int c = 0; c < Size; ++c) edge[c] = normalized(minus(p[(c + 1) % Size], p[c]));
    for (int c = 0; c < Size; ++c) {
        alignas(64) float angle[kFloatLanes];
        const VecF lanes_angle = safe_acos_approx(-dot(edge[(c + Size - 1) % Size], edge[c]));
        std::memcpy(angle, &lanes_angle, sizeof angle);
        for (int k = 0; k < lanes; ++k) corner_angles[first[k] + c] = angle[k];
    }
    // normalize_v3: multiply by 1/length; zero → +z.
    const VecF squared = n.x * n.x + n.y * n.y + n.z * n.z;
    const MaskF ok = squared > 1.0e-35f;
    const VecF inverse = 1.0f / sqrt_lanes(ok ? squared : splat(1.0f));
    Staging3 normal;
    normal.store({ok ? n.x * inverse : splat(0.0f), ok ? n.y * inverse : splat(0.0f), ok ? n.z * inverse : splat(1.0f)});
    for (int k = 0; k < lanes; ++k) {
        float* out = face_normals + 3 * std::size_t(faces[k]);
        out[0] = normal.x[k];
        out[1] = normal.y[k];
        out[2] = normal.z[k];
    }
}

// One face of any size, one lane's arithmetic.
void face_single(const std::uint32_t* face_start, const std::uint32_t* corner_vertex, const float* positions,
                 std::size_t face, float* face_normals, float* corner_angles) {
    const std::uint32_t first = face_start[face], last = face_start[face + 1] - 1;
    const auto point = [&](std::uint32_t c) {
        const float* q = positions + 3 * std::size_t(corner_vertex[c]);
        return Lanes3{splat(q[0]), splat(q[1]), splat(q[2])};
    };
    Lanes3 n{splat(0.0f), splat(0.0f), splat(0.0f)};
    Lanes3 previous = point(last);
    Lanes3 edge_in = normalized(minus(point(first), previous));
    for (std::uint32_t c = first; c <= last; ++c) {
        const Lanes3 current = point(c);
        n.x += (previous.y - current.y) * (previous.z + current.z);
        n.y += (previous.z - current.z) * (previous.x + current.x);
        n.z += (previous.x - current.x) * (previous.y + current.y);
        previous = current;
        const Lanes3 edge_out = normalized(minus(point(c == last ? first : c + 1), current));
        corner_angles[c] = safe_acos_approx(-dot(edge_in, edge_out))[0];
        edge_in = edge_out;
    }
    const float squared = n.x[0] * n.x[0] + n.y[0] * n.y[0] + n.z[0] * n.z[0];
    float* out = face_normals + 3 * face;
    if (squared > 1.0e-35f) {
        const float inverse = 1.0f / std::sqrt(squared);
        out[0] = n.x[0] * inverse;
        out[1] = n.y[0] * inverse;
        out[2] = n.z[0] * inverse;
    } else {
        out[0] = out[1] = 0.0f;
        out[2] = 1.0f;
    }
}

void face_normals_range(const std::uint32_t* face_start, const std::uint32_t* corner_vertex, const float* positions,
                        const std::uint32_t* faces, std::size_t count, int size, float* face_normals,
                        float* corner_angles) {
    for (std::size_t i = 0; i < count;) {
        const int lanes = int(std::min<std::size_t>(kFloatLanes, count - i));
        if (size == 4) face_batch<4>(face_start, corner_vertex, positions, faces + i, lanes, face_normals, corner_angles);
        else if (size == 3) face_batch<3>(face_start, corner_vertex, positions, faces + i, lanes, face_normals, corner_angles);
        else face_single(face_start, corner_vertex, positions, faces[i], face_normals, corner_angles);
        i += size == 3 || size == 4 ? std::size_t(lanes) : 1;
    }
}

// The Blender normals (object space) of `lanes` vertices from `begin`: the
// sums one vertex at a time (a vertex's faces vary in number: lanes of
// vertices spent their time gathering), the normalization in lanes. Spare
// lanes hold zeros.
Lanes3 blender_normals(const NormalSources& sources, const float* positions, std::size_t begin, int lanes) {
    Staging3 sum{};
    for (int k = 0; k < lanes; ++k) {
        const std::size_t vertex = begin + std::size_t(k);
        const std::uint32_t from = sources.vertex_start[vertex], to = sources.vertex_start[vertex + 1];
        float x = 0.0f, y = 0.0f, z = 0.0f;
        if (from == to) {  // a vertex that no face uses: its normalized position
            x = positions[3 * vertex];
            y = positions[3 * vertex + 1];
            z = positions[3 * vertex + 2];
        }
        // Σ face normal × corner angle over the faces in ascending order, the
        // three components side by side in one 4-float vector (the fourth
        // reads the next face's x, or the padding after the last face, and
        // is dropped).
        Quad acc = {x, y, z, 0.0f};
        for (std::uint32_t i = from; i < to; ++i) {
            const Quad f = load_quad(sources.face_normals + 3 * std::size_t(sources.incident_face[i]));
            acc += f * (sources.corner_angles[sources.incident_corner[i]] - Quad{});
        }
        sum.x[k] = acc[0];
        sum.y[k] = acc[1];
        sum.z[k] = acc[2];
    }
    return normalized(sum.load());
}

void vertex_normals_range(const NormalSources& sources, const float* positions, std::size_t begin, std::size_t end,
                          float* normals_out) {
    for (std::size_t v = begin; v < end; v += kFloatLanes) {
        const int lanes = int(std::min<std::size_t>(kFloatLanes, end - v));
        Staging3 n;
        n.store(blender_normals(sources, positions, v, lanes));
        for (int k = 0; k < lanes; ++k) {
            float* out = normals_out + 3 * (v - begin + std::size_t(k));
            out[0] = n.x[k];
            out[1] = n.y[k];
            out[2] = n.z[k];
        }
    }
}

void lobes_from_params(int order, std::size_t count, const float* params, float* axes_out, float* bands_out) {
    const int ppl = 2 + order;
    for (std::size_t i = 0; i < count; i += kFloatLanes) {
        const int lanes = int(std::min<std::size_t>(kFloatLanes, count - i));
        VecF X, Y;
        for (int k = 0; k < kFloatLanes; ++k) {
            const float* p = params + (i + std::size_t(std::min(k, lanes - 1))) * ppl;
            X[k] = p[0];
            Y[k] = p[1];
        }
        // lambert_to_axis (zh_fit.hpp) in float: (s X, s Y, 1 − r²/2) with
        // s = sqrt(1 − r²/4) is a unit vector by construction (to float
        // rounding; the shader normalizes again); beyond the disc r = 2 the
        // point is pulled onto its rim; a non-finite one is +z.
        VecF r2 = X * X + Y * Y;
        const MaskF usable = r2 - r2 == 0.0f;
        const MaskF outside = usable & (r2 > 4.0f);
        const VecF pull = 2.0f / sqrt_lanes(outside ? r2 : splat(4.0f));
        X = outside ? X * pull : X;
        Y = outside ? Y * pull : Y;
        r2 = outside ? splat(4.0f) : r2;
        const VecF rest = 1.0f - 0.25f * r2;
        const VecF s = sqrt_lanes(rest > 0.0f ? rest : splat(0.0f));
        const VecF ax = usable ? s * X : splat(0.0f), ay = usable ? s * Y : splat(0.0f),
                   az = usable ? 1.0f - 0.5f * r2 : splat(1.0f);
        for (int k = 0; k < lanes; ++k) {
            float* a = axes_out + 3 * (i + std::size_t(k));
            a[0] = ax[k];
            a[1] = ay[k];
            a[2] = az[k];
            std::memcpy(bands_out + (i + std::size_t(k)) * order, params + (i + std::size_t(k)) * ppl + 2,
                        sizeof(float) * std::size_t(order));
        }
    }
}

// A row-major 3 × 3 matrix with every entry in all lanes, made once per
// range (a broadcast per entry per batch was a sixth of the frames' time).
struct LaneMatrix {
    VecF m[9];
    explicit LaneMatrix(const float* entries) {
        for (int i = 0; i < 9; ++i) m[i] = splat(entries[i]);
    }
};

PENUMBRA_LANES_INLINE Lanes3 transform(const LaneMatrix& a, const Lanes3& v) {
    const VecF* m = a.m;
    return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z,
            m[6] * v.x + m[7] * v.y + m[8] * v.z};
}

// Duff et al. 2017's tangent of a unit normal (mesh_frames.cpp's
// basis_from_normal).
PENUMBRA_LANES_INLINE Lanes3 basis_tangent(const Lanes3& n) {
    const VecF sign = n.z < 0.0f ? splat(-1.0f) : splat(1.0f);
    const VecF a = -1.0f / (sign + n.z);
    const VecF c = n.x * n.y * a;
    return {1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x};
}

// The first `count` lanes of (x, y, z) into three rows `stride` apart, from
// `column` on.
PENUMBRA_LANES_INLINE void store_rows(float* rows, std::size_t stride, std::size_t column, const Lanes3& v, int count) {
    std::memcpy(rows + column, &v.x, sizeof(float) * std::size_t(count));
    std::memcpy(rows + stride + column, &v.y, sizeof(float) * std::size_t(count));
    std::memcpy(rows + 2 * stride + column, &v.z, sizeof(float) * std::size_t(count));
}

// A batch of `count` ≤ kFloatLanes vertices from `begin` (a short batch repeats
// its last vertex in the spare lanes).
void frames_batch(const FrameTransform& tr, const LaneMatrix& linear, const LaneMatrix& normal_matrix,
                  const NormalSources& sources, const float* positions,
                  const std::uint32_t* neighbours, std::size_t begin, int count, std::size_t chunk_begin,
                  std::size_t stride, float* normals_out, float* tangents_out, float* positions_out,
                  FrameCounts& counts) {
    const Lanes3 local = blender_normals(sources, positions, begin, count);
    Staging3 p_lanes, q_lanes;
    alignas(64) std::int32_t own_lanes[kFloatLanes];
    for (int k = 0; k < kFloatLanes; ++k) {
        const std::size_t v = begin + std::size_t(std::min(k, count - 1));
        const std::uint32_t neighbour = neighbours[v];
        own_lanes[k] = neighbour == v ? -1 : 0;
        p_lanes.set(k, positions + 3 * v);
        q_lanes.set(k, positions + 3 * std::size_t(neighbour));
    }
    const Lanes3 p = p_lanes.load(), q = q_lanes.load();
    MaskF own;
    std::memcpy(&own, own_lanes, sizeof own);
    // The world normal, unit; zero or non-finite → +z.
    Lanes3 n = transform(normal_matrix, local);
    const VecF squared = dot(n, n);
    const MaskF usable = finite(squared) & (squared > 1e-30f);
    const VecF inverse = 1.0f / sqrt_lanes(usable ? squared : splat(1.0f));
    n = {usable ? n.x * inverse : splat(0.0f), usable ? n.y * inverse : splat(0.0f),
         usable ? n.z * inverse : splat(1.0f)};
    const Lanes3 world = transform(linear, p);
    const Lanes3 edge = transform(linear, minus(q, p));
    // The edge projected onto the tangent plane; within ~0.06° of n it gives
    // no usable direction.
    const VecF along = dot(n, edge);
    Lanes3 t{edge.x - n.x * along, edge.y - n.y * along, edge.z - n.z * along};
    const VecF t_length = sqrt_lanes(dot(t, t)), edge_length = sqrt_lanes(dot(edge, edge));
    const MaskF from_edge = ~own & (t_length > 1e-3f * edge_length) & finite(t_length);
    const VecF t_inverse = 1.0f / (from_edge ? t_length : splat(1.0f));
    const Lanes3 basis = basis_tangent(n);
    t = {from_edge ? t.x * t_inverse : basis.x, from_edge ? t.y * t_inverse : basis.y,
         from_edge ? t.z * t_inverse : basis.z};
    for (int k = 0; k < count; ++k) {
        counts.repaired += usable[k] ? 0 : 1;
        counts.fallback += from_edge[k] ? 0 : 1;
    }
    const std::size_t column = begin - chunk_begin;
    store_rows(normals_out, stride, column, n, count);
    store_rows(tangents_out, stride, column, t, count);
    store_rows(positions_out, stride, column, {world.x + tr.offset[0], world.y + tr.offset[1], world.z + tr.offset[2]},
               count);
}

void frames_range(const FrameTransform& transform, const NormalSources& sources, const float* positions,
                  const std::uint32_t* neighbours, std::size_t begin, std::size_t end, std::size_t stride,
                  float* normals_out, float* tangents_out, float* positions_out, FrameCounts& counts) {
    const LaneMatrix linear(transform.linear), normal_matrix(transform.normal_matrix);
    for (std::size_t v = begin; v < end; v += kFloatLanes)
        frames_batch(transform, linear, normal_matrix, sources, positions, neighbours, v,
                     int(std::min<std::size_t>(kFloatLanes, end - v)), begin, stride, normals_out, tangents_out,
                     positions_out, counts);
}

// acc + a·b, fused where the target has FMA (an explicit fma is not
// contraction, which this file turns off).
PENUMBRA_LANES_INLINE float multiply_add(float a, float b, float acc) {
#if HWY_TARGET <= HWY_AVX2
    return std::fma(a, b, acc);
#else
    return a * b + acc;
#endif
}

PENUMBRA_LANES_INLINE Quad multiply_add(Quad a, Quad b, Quad acc) {
#if HWY_TARGET <= HWY_AVX2
    return __builtin_ia32_vfmaddps(a, b, acc);
#else
    return a * b + acc;
#endif
}

// D parameters per vertex, a multiple of 4 known at compile time: the
// accumulator stays in registers (groups of 4) across a block's features;
// with d a run-time value it went through memory for every feature, each add
// waiting on the last store.
namespace hn = hwy::HWY_NAMESPACE;

PENUMBRA_LANES_INLINE float load_half(const std::uint16_t* p) {
    const hn::FixedTag<float, 1> d1;
    const hn::FixedTag<hwy::float16_t, 1> dh1;
    return hn::GetLane(hn::PromoteTo(d1, hn::LoadU(dh1, reinterpret_cast<const hwy::float16_t*>(p))));
}

// Four binary16 weights as floats: one F16C instruction on the AVX2 and
// AVX-512 targets, Highway's integer emulation on the others (one lane at
// a time on the scalar one).
PENUMBRA_LANES_INLINE Quad load_half_quad(const std::uint16_t* p) {
#if HWY_TARGET == HWY_SCALAR
    return Quad{load_half(p), load_half(p + 1), load_half(p + 2), load_half(p + 3)};
#else
    const hn::FixedTag<float, 4> d4;
    const hn::FixedTag<hwy::float16_t, 4> dh4;
    alignas(16) float values[4];
    hn::Store(hn::PromoteTo(d4, hn::LoadU(dh4, reinterpret_cast<const hwy::float16_t*>(p))), d4, values);
    return load_quad(values);
#endif
}

#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX2
// AVX2 and AVX-512 (F16C): eight lanes a row where the parameters allow,
// the conversion reading memory itself; a row of 12 is then one
// conversion and one fused multiply-add of 8 lanes plus one of 4 instead of
// three of 4, and the loop is the pass's one stream from memory
// (docs/visibility-benchmark.md).
typedef float Oct __attribute__((vector_size(8 * sizeof(float))));
constexpr bool kOctets = true;
PENUMBRA_LANES_INLINE Oct load_half_oct(const std::uint16_t* p) {
    return Oct(_mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p))));
}
PENUMBRA_LANES_INLINE Oct multiply_add(Oct a, Oct b, Oct acc) { return Oct(_mm256_fmadd_ps(__m256(a), __m256(b), __m256(acc))); }
#else
// Elsewhere every row goes in groups of 4; the names below are only
// declared, for the branch Accumulator never takes there.
typedef Quad Oct;
constexpr bool kOctets = false;
PENUMBRA_LANES_INLINE Oct load_half_oct(const std::uint16_t* p) { return load_half_quad(p); }
#endif

// D parameters per vertex (a multiple of 4): the accumulator, groups of 8
// lanes where the target has them, then groups of 4.
template <int D>
struct Accumulator {
    static constexpr int kOcts = kOctets ? D / 8 : 0;
    static constexpr int kQuads = (D - 8 * kOcts) / 4;
    Oct oct[kOcts > 0 ? kOcts : 1];
    Quad quad[kQuads > 0 ? kQuads : 1];

    PENUMBRA_LANES_INLINE void load(const float* p) {
        for (int o = 0; o < kOcts; ++o) std::memcpy(&oct[o], p + 8 * o, sizeof(Oct));
        for (int q = 0; q < kQuads; ++q) quad[q] = load_quad(p + 8 * kOcts + 4 * q);
    }
    // += feature · the row of D binary16 weights at w.
    PENUMBRA_LANES_INLINE void add(float feature, const std::uint16_t* w) {
        if constexpr (kOcts > 0) {
            const Oct f8 = feature - Oct{};
            for (int o = 0; o < kOcts; ++o) oct[o] = multiply_add(f8, load_half_oct(w + 8 * o), oct[o]);
        }
        const Quad f4 = feature - Quad{};
        for (int q = 0; q < kQuads; ++q) quad[q] = multiply_add(f4, load_half_quad(w + 8 * kOcts + 4 * q), quad[q]);
    }
    PENUMBRA_LANES_INLINE void store(float* out) const {
        for (int o = 0; o < kOcts; ++o) std::memcpy(out + 8 * o, &oct[o], sizeof(Oct));
        for (int q = 0; q < kQuads; ++q) std::memcpy(out + 8 * kOcts + 4 * q, &quad[q], sizeof(Quad));
    }
};

template <int D>
void apply_pose_blocks_fixed(const PoseBlocks& b, const float* features, std::size_t begin, std::size_t end,
                             float* params_out, std::size_t stride) {
    static_assert(D % 4 == 0);
    const std::uint16_t* w = b.weights + b.weight_offsets[begin];
    for (std::size_t v = begin; v < end; ++v) {
        Accumulator<D> acc;
        acc.load(b.bias + v * D);
        for (std::uint32_t e = b.joint_offsets[v]; e < b.joint_offsets[v + 1]; ++e) {
            const float* f = features + b.feature_offsets[b.joint_index[e]];
            const int m = b.block_directions[e];
            // The block's scale goes on the feature: one product per feature,
            // exact (a power of two).
            const float scale = b.scales[e];
            for (int a = 0; a < m; ++a, w += D) acc.add(f[a] * scale, w);
        }
        if (!stride) {
            acc.store(params_out + (v - begin) * D);
            continue;
        }
        float values[D];
        acc.store(values);
        for (int i = 0; i < D; ++i) params_out[i * stride + (v - begin)] = values[i];
    }
}

void apply_pose_blocks_any(const PoseBlocks& b, const float* features, std::size_t begin, std::size_t end,
                           float* params_out, std::size_t stride) {
    const int d = b.d;
    const std::uint16_t* w = b.weights + b.weight_offsets[begin];
    for (std::size_t v = begin; v < end; ++v) {
        // Column v − begin of the rows, or the vertex's d values.
        const std::size_t step = stride ? stride : 1;
        float* acc = params_out + (stride ? v - begin : (v - begin) * d);
        for (int i = 0; i < d; ++i) acc[i * step] = b.bias[v * d + i];
        for (std::uint32_t e = b.joint_offsets[v]; e < b.joint_offsets[v + 1]; ++e) {
            const std::uint32_t first = b.feature_offsets[b.joint_index[e]];
            const int m = b.block_directions[e];
            for (int a = 0; a < m; ++a, w += d) {
                const float fa = features[first + a] * b.scales[e];
                for (int i = 0; i < d; ++i) acc[i * step] = multiply_add(fa, load_half(w + i), acc[i * step]);
            }
        }
    }
}

void apply_pose_blocks(const PoseBlocks& blocks, const float* features, std::size_t begin, std::size_t end,
                       float* params_out, std::size_t stride) {
    // 2 and 4 lobes at order 4 (2 + 4 parameters per lobe), the usual models.
    switch (blocks.d) {
        case 12: return apply_pose_blocks_fixed<12>(blocks, features, begin, end, params_out, stride);
        case 24: return apply_pose_blocks_fixed<24>(blocks, features, begin, end, params_out, stride);
        default: return apply_pose_blocks_any(blocks, features, begin, end, params_out, stride);
    }
}

}  // namespace penumbra::visibility::detail::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace penumbra::visibility::detail {

HWY_EXPORT(apply_pose_blocks);
void apply_pose_blocks(const PoseBlocks& blocks, const float* features, std::size_t begin, std::size_t end,
                       float* params_out, std::size_t stride) {
    HWY_DYNAMIC_DISPATCH(apply_pose_blocks)(blocks, features, begin, end, params_out, stride);
}

HWY_EXPORT(face_normals_range);
void face_normals_range(const std::uint32_t* face_start, const std::uint32_t* corner_vertex, const float* positions,
                        const std::uint32_t* faces, std::size_t count, int size, float* face_normals,
                        float* corner_angles) {
    HWY_DYNAMIC_DISPATCH(face_normals_range)(face_start, corner_vertex, positions, faces, count, size, face_normals,
                                             corner_angles);
}

HWY_EXPORT(vertex_normals_range);
void vertex_normals_range(const NormalSources& sources, const float* positions, std::size_t begin, std::size_t end,
                          float* normals_out) {
    HWY_DYNAMIC_DISPATCH(vertex_normals_range)(sources, positions, begin, end, normals_out);
}

HWY_EXPORT(lobes_from_params);
void lobes_from_params(int order, std::size_t count, const float* params, float* axes_out, float* bands_out) {
    HWY_DYNAMIC_DISPATCH(lobes_from_params)(order, count, params, axes_out, bands_out);
}

HWY_EXPORT(frames_range);
void frames_range(const FrameTransform& transform, const NormalSources& sources, const float* positions,
                  const std::uint32_t* neighbours, std::size_t begin, std::size_t end, std::size_t stride,
                  float* normals_out, float* tangents_out, float* positions_out, FrameCounts& counts) {
    HWY_DYNAMIC_DISPATCH(frames_range)(transform, sources, positions, neighbours, begin, end, stride, normals_out,
                                       tangents_out, positions_out, counts);
}

}  // namespace penumbra::visibility::detail
#endif  // HWY_ONCE
