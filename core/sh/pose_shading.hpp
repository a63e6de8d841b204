// Batched shading of one pose (paper §4, runtime steps 2–5 of §4.3): every
// vertex carries its visibility as a few zonal-harmonic (ZH) lobes in its own
// tangent frame; a vertex shades to lᵀ T v, the SH lighting l dotted with the
// visibility v convolved by a 1D-BRDF operator T (sh/brdf_operator.hpp), with
// l and v brought into the frame T is written in. Design, costs and accuracy:
// docs/sh-engine.md; measurements: docs/sh-shading-benchmark.md.
//
// Conventions (the visibility baker writes what this reads)
// ---------------------------------------------------------
// * SH: sh/basis.hpp. Lighting is (order², 3) RGB coefficients of the world
//   radiance (world axes of common/latlong.hpp), e.g. from project_equirectangular.
// * A vertex's local frame is (t, b, n): n = normalize(normal),
//   t = normalize(tangent − (tangent·n) n) (Gram–Schmidt, so the tangent need
//   not be exactly orthogonal), b = n × t. Local coordinates (x, y, z) mean
//   the world direction x t + y b + z n.
// * A ZH lobe is an axis in local coordinates (normalized here) and `order`
//   band coefficients g_l; the vertex's visibility is paper Eq. 1,
//   v_lm = Σ_lobes sqrt(4π/(2l+1)) g_l y_lm(axis).
// * Normalization: under uniform radiance 1 (l = √(4π) e_0 per channel) the
//   diffuse shade is the cosine-weighted visibility (ambient occlusion) in
//   [0, 1]; a fully visible vertex (v = √(4π) e_0) shades to exactly 1.
//
// Models (what each vertex computes; V = ZH visibility, L = lighting, both
// truncated to `order` bands; the integrals are exact for these truncations)
// * diffuse:     (1/π) ∫_{ω·n>0} (ω·n) V(ω) L(ω) dω.
// * phong:       ((α+1)/2π) ∫_{ω·r>0} (ω·r)^α V(ω) L(ω) dω, with the local
//   viewer r = reflect(−w, n) = 2(n·w) n − w, w = normalize(camera − position).
//   The operator integrates the hemisphere about r (paper Eq. 2): light from
//   below the surface's tangent plane is removed only by V. When the camera
//   is behind the tangent plane (n·w < 0) r would point below the surface; it
//   is clamped to the horizon, r = −normalize(w − (n·w) n), which is
//   continuous at n·w = 0. When that is undefined (w = −n exactly, or the
//   camera at the vertex) r = n.
// * translucent (thin membrane, paper §4.1 after Sloan et al. 2005): the
//   diffuse term above (front face, shadowed by V) plus, per channel c,
//   transmission[c] · (1/π) ∫_{ω·n<0} (−ω·n) L(ω) dω — an unshadowed
//   clamped-cosine lobe about −n, pre-tabulated as ZH.
//
// How (docs/sh-engine.md has the derivation and measurements): T commutes
// with rotations about its z axis, so only a frame whose z is n (or r)
// matters. The lobes are turned into the frame F' = Rz(φ) Ry(θ) that takes z
// to n (or r), expanded with Eq. 1, multiplied by T, and the single-channel
// result u is rotated back to world coordinates once, as
// D(F') = Dz(φ) · Xᵀ · Dz(θ) · X with X the fixed SH rotation of a 90° turn
// about x (Ry(θ) = Rx(90°)ᵀ Rz(θ) Rx(90°)) and Dz cheap (cos/sin of mφ):
// shade_c = l_cᵀ D(F') u. Vertices go in batches of one SIMD register of
// the buffers' precision, threads take contiguous ranges, nothing is
// allocated per vertex. Float buffers are shaded in float (twice the SIMD
// lanes; within 3e-5 of double, tested), double buffers in double.
#pragma once

#include <array>
#include <cstddef>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/setting.hpp"
#include "common/simd_target.hpp"
#include "sh/basis.hpp"
#include "sh/brdf_operator.hpp"

namespace penumbra::sh {

namespace detail {
template <typename S>
struct PoseShadingSetup;
}  // namespace detail

enum class ShadingModel { diffuse, phong, translucent };

struct ShadingParameters {
    ShadingModel model = ShadingModel::diffuse;
    // Normalized Phong exponent α >= 0 (+infinity allowed: mirror limit).
    double phong_exponent = 16.0;
    static constexpr Range<double> phong_exponent_range{0.0, unbounded};
    // World position of the camera (phong: local viewer).
    Eigen::Vector3d camera = Eigen::Vector3d::Zero();
    // Translucent: RGB weight of the transmitted (back-face) lobe, finite.
    std::array<double, 3> transmission{0.5, 0.5, 0.5};
    // Worker threads (common/setting.hpp threads_range; 0: all). Results do
    // not depend on it (each vertex is computed the same way on any thread).
    int threads = 0;
};

// Views into caller-owned, row-major arrays for N vertices with C lobes each.
// Real is float or double, and so is the arithmetic.
template <typename Real>
struct PoseBuffers {
    std::size_t vertex_count = 0;      // N
    int lobes_per_vertex = 1;          // C >= 1
    const Real* lobe_axes = nullptr;   // (N, C, 3) local frame
    const Real* lobe_bands = nullptr;  // (N, C, order) g_l
    const Real* normals = nullptr;     // (N, 3) world
    const Real* tangents = nullptr;    // (N, 3) world
    const Real* positions = nullptr;   // (N, 3) world; needed by phong only
    Real* rgb = nullptr;               // (N, 3) output
    Real* visibility = nullptr;        // (N,) optional output: cosine-weighted
                                       // visibility (1/π)∫_H (ω·n) V, the AO
    // Instead of lobe_axes and lobe_bands: (N, C, 2 + order), the visibility
    // model's lobe parameters (visibility/zh_fit.hpp: the axis as Lambert
    // azimuthal equal-area (X, Y) about +z, then the bands), turned into axes
    // in the lanes (a non-finite (X, Y) gives +z, as lambert_to_axis does).
    const Real* lobe_params = nullptr;
};

// A vertex is invalid when its normal is zero or non-finite, its tangent is
// non-finite or within 1e-6 rad of its normal (after Gram–Schmidt nothing is
// left), a band or (phong) its position is non-finite, or a lobe axis is zero
// or non-finite while that lobe's bands are not all zero (a zero axis with zero
// bands is an unused lobe and is skipped). An invalid vertex shades to 0 (and
// visibility 0) and is counted here; it never throws.
struct ShadingStats {
    std::size_t invalid_vertices = 0;
};

// One block of float inputs in structure-of-arrays layout: each component a
// row of its own, rows `stride` floats apart, so the kernel loads whole lane
// vectors instead of gathering every lane. What the run time writes
// (visibility/frame_shading.cpp). Every row must be readable and writable
// up to vertex_count rounded up to a multiple of 16 (the widest lanes); the
// values past vertex_count are read, shaded and discarded, so keep them
// finite (zeros are best: they cost nothing extra). The frames must be
// orthonormal already (unit normals, unit tangents orthogonal to them, as
// the run time's are): a block skips the normalization and Gram–Schmidt,
// and only a non-finite position (Phong) or band makes a vertex invalid.
struct PoseBlock {
    std::size_t vertex_count = 0;
    std::size_t stride = 0;
    const float* normals = nullptr;      // 3 rows x, y, z (world)
    const float* tangents = nullptr;     // 3 rows (world)
    const float* positions = nullptr;    // 3 rows (world; Phong)
    const float* lobe_params = nullptr;  // lobes × (2 + order) rows, as PoseBuffers::lobe_params by component
    float* rgb = nullptr;                // 3 rows, output
    float* visibility = nullptr;         // 1 row, output (optional)
};

class PoseShader;

// One call's constants (operator, lighting, rotation tables, the kernel for
// this CPU), made once by PoseShader::prepare and used for any number of
// vertex ranges: the run time (visibility/frame_shading.hpp) fuses the
// shading with its other per-vertex steps, block by block. Immutable, so
// several threads may shade ranges at once.
class PreparedShading {
public:
    // Shades vertices [begin, end) of `buffers` (lobes_per_vertex as
    // prepared; positions needed for Phong); returns how many were invalid.
    std::size_t shade_range(const PoseBuffers<float>& buffers, std::size_t begin, std::size_t end) const;
    // The same for a block in structure-of-arrays layout.
    std::size_t shade_block(const PoseBlock& block) const;

private:
    friend class PoseShader;
    std::shared_ptr<const detail::PoseShadingSetup<float>> setup_;
    void (*run_)(const detail::PoseShadingSetup<float>&, const PoseBuffers<float>&, std::size_t, std::size_t,
                 std::size_t&) = nullptr;
    void (*run_block_)(const detail::PoseShadingSetup<float>&, const PoseBlock&, std::size_t&) = nullptr;
};

class PoseShader {
public:
    // 1 <= order <= max_order, else ArgumentError. Builds the diffuse
    // operator and the fixed 90° rotation; cheap (microseconds).
    explicit PoseShader(int order);

    int order() const { return order_; }

    // Shades every vertex of `buffers` under `lighting` ((order², 3), finite).
    // Throws ArgumentError for a wrong lighting shape, non-finite lighting,
    // camera or transmission, α < 0 or NaN, missing buffers, C < 1 or
    // threads < 0; never for per-vertex data (see ShadingStats). Thread-safe:
    // one shader may serve concurrent calls.
    ShadingStats shade(const Eigen::MatrixXd& lighting, const ShadingParameters& parameters,
                       const PoseBuffers<float>& buffers) const;
    ShadingStats shade(const Eigen::MatrixXd& lighting, const ShadingParameters& parameters,
                       const PoseBuffers<double>& buffers) const;

    // shade()'s checks and set-up without the buffers, for PreparedShading.
    // Throws as shade() does for the lighting and parameters.
    PreparedShading prepare(const Eigen::MatrixXd& lighting, const ShadingParameters& parameters, int lobes,
                            bool want_visibility) const;

    // The operator T a model uses: the diffuse operator for diffuse and
    // translucent, phong_zonal_operator(order, α) for phong (cached per
    // exponent; the cache is emptied when it holds 16).
    std::shared_ptr<const ZonalOperator> operator_for(ShadingModel model, double phong_exponent) const;

    // Zonal coefficients h_l of the clamped cosine (1/π) max(0, cosθ) about
    // +z: the translucent back lobe, about −n.
    const std::array<double, max_order>& clamped_cosine_zonal() const { return cosine_zonal_; }

private:
    struct SparseEntry {
        int row, column;
        double value;
    };

    void check_call(const Eigen::MatrixXd& lighting, const ShadingParameters& parameters, int lobes) const;
    template <typename Real>
    ShadingStats shade_impl(const Eigen::MatrixXd& lighting, const ShadingParameters& parameters,
                            const PoseBuffers<Real>& buffers) const;
    detail::PoseShadingSetup<double> make_setup(const ZonalOperator& op, const Eigen::MatrixXd& lighting,
                                                const ShadingParameters& parameters, int lobes,
                                                bool want_visibility) const;
    template <typename Real>
    static ShadingStats run_threads(const detail::PoseShadingSetup<Real>& setup, const PoseBuffers<Real>& buffers,
                                    int thread_count);

    int order_;
    std::shared_ptr<const ZonalOperator> diffuse_;
    // X = D(Rx(90°)) and Xᵀ, non-zero entries only, by row.
    std::vector<SparseEntry> quarter_turn_, quarter_turn_transposed_;
    std::array<double, max_order> cosine_zonal_{};

    mutable std::mutex cache_mutex_;
    mutable std::map<double, std::shared_ptr<const ZonalOperator>> phong_cache_;
};

// The SIMD target the hot loop runs on, under the SH engine's names (bound
// as _penumbra.sh.simd_target, simd_targets and force_simd_target): the
// choice is common/simd_target.hpp's, one for the whole process, shared with
// the visibility and lights kernels.
using penumbra::force_simd_target;
using penumbra::simd_target;
using penumbra::simd_targets;

}  // namespace penumbra::sh
