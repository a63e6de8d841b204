// Batched pose shading (header: the conventions and models; docs/sh-engine.md:
// the derivation and measurements). This file holds what a call does once
// (operators, lighting, checks, threads); the per-vertex hot loop is
// sh/pose_shading_kernel.cpp, compiled per SIMD target and chosen at run time.
#include "sh/pose_shading.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <type_traits>

#include <Eigen/Geometry>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "sh/basis.hpp"
#include "sh/legendre.hpp"
#include "sh/pose_shading_setup.hpp"
#include "sh/rotation.hpp"

namespace penumbra::sh {

using detail::PoseShadingSetup;

namespace {

template <typename Real>
detail::RangeFunction<Real> range_function(int order) {
    if constexpr (std::is_same_v<Real, float>) return detail::range_function_float(order);
    else return detail::range_function_double(order);
}

}  // namespace

namespace detail {

PoseShadingSetup<float> to_float(const PoseShadingSetup<double>& d) {
    const auto round = [](const auto& from, auto& to) {
        for (std::size_t i = 0; i < from.size(); ++i) to[i] = float(from[i]);
    };
    PoseShadingSetup<float> f;
    f.order = d.order;
    f.lobes = d.lobes;
    f.model = d.model;
    f.want_visibility = d.want_visibility;
    f.block_offset = d.block_offset;
    f.x_columns = d.x_columns;
    f.xt_columns = d.xt_columns;
    f.blocks.resize(d.blocks.size());
    f.x_values.resize(d.x_values.size());
    f.xt_values.resize(d.xt_values.size());
    f.lighting.resize(d.lighting.size());
    f.back.resize(d.back.size());
    round(d.camera, f.camera);
    round(d.blocks, f.blocks);
    round(d.x_values, f.x_values);
    round(d.xt_values, f.xt_values);
    for (std::size_t i = 0; i < d.lighting.size(); ++i) {
        round(d.lighting[i], f.lighting[i]);
        round(d.back[i], f.back[i]);
    }
    round(d.zh_scale, f.zh_scale);
    round(d.ao_weight, f.ao_weight);
    round(d.legendre_diagonal, f.legendre_diagonal);
    round(d.legendre_first, f.legendre_first);
    round(d.legendre_a, f.legendre_a);
    round(d.legendre_b, f.legendre_b);
    return f;
}

}  // namespace detail

PoseShader::PoseShader(int order) : order_(order) {
    check_order(order);
    diffuse_ = std::make_shared<const ZonalOperator>(diffuse_zonal_operator(order));

    // X = D(Rx(90°)): Ry(θ) = Rx(90°)ᵀ Rz(θ) Rx(90°).
    const Eigen::Matrix3d quarter_turn = Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
    const ShRotation rotation(order, quarter_turn);
    for (int l = 0; l < order; ++l) {
        const Eigen::MatrixXd& block = rotation.band(l);
        for (int i = 0; i < 2 * l + 1; ++i)
            for (int j = 0; j < 2 * l + 1; ++j) {
                // Entries that vanish analytically come out at rounding level.
                if (std::abs(block(i, j)) < 1e-14) continue;
                quarter_turn_.push_back({l * l + i, l * l + j, block(i, j)});
                quarter_turn_transposed_.push_back({l * l + j, l * l + i, block(i, j)});
            }
    }
    const auto by_row = [](const SparseEntry& a, const SparseEntry& b) {
        return a.row != b.row ? a.row < b.row : a.column < b.column;
    };
    std::sort(quarter_turn_transposed_.begin(), quarter_turn_transposed_.end(), by_row);
    // The kernel stores quarter_turn_width(l) entries per row of band l.
    for (const std::vector<SparseEntry>* entries : {&quarter_turn_, &quarter_turn_transposed_}) {
        std::vector<int> per_row(std::size_t(order) * order, 0);
        for (const SparseEntry& e : *entries) ++per_row[e.row];
        for (int l = 0; l < order; ++l)
            for (int i = l * l; i < (l + 1) * (l + 1); ++i)
                if (per_row[i] > detail::quarter_turn_width(l))
                    throw std::logic_error("pose shading: a row of the 90° SH rotation has more non-zeros than stored");
    }

    // h_l = ∫_{S²} (1/π) max(0, cosθ) y_l0 = √(4π) T_d[l0, 00] (y_00 = 1/√(4π)).
    for (int l = 0; l < order; ++l)
        cosine_zonal_[l] = std::sqrt(4.0 * std::numbers::pi) * diffuse_->blocks[0](l, 0);
}

std::shared_ptr<const ZonalOperator> PoseShader::operator_for(ShadingModel model, double phong_exponent) const {
    if (model != ShadingModel::phong) return diffuse_;
    if (!(phong_exponent >= 0.0))
        throw ArgumentError("the Phong exponent must be >= 0, got " + std::to_string(phong_exponent));
    {
        std::lock_guard<std::mutex> lock(cache_mutex_);
        const auto found = phong_cache_.find(phong_exponent);
        if (found != phong_cache_.end()) return found->second;
    }
    auto made = std::make_shared<const ZonalOperator>(phong_zonal_operator(order_, phong_exponent));
    std::lock_guard<std::mutex> lock(cache_mutex_);
    if (phong_cache_.size() >= 16) phong_cache_.clear();
    phong_cache_.emplace(phong_exponent, made);
    return made;
}

void PoseShader::check_call(const Eigen::MatrixXd& lighting, const ShadingParameters& parameters, int lobes) const {
    const int coefficients = coefficient_count(order_);
    if (lighting.rows() != coefficients || lighting.cols() != 3)
        throw ArgumentError("lighting must have shape (order², 3) = (" + std::to_string(coefficients) +
                            ", 3), got (" + std::to_string(lighting.rows()) + ", " +
                            std::to_string(lighting.cols()) + ")");
    if (!lighting.allFinite()) throw ArgumentError("lighting has a NaN or infinite coefficient");
    if (lobes < 1) throw ArgumentError("each vertex needs at least one ZH lobe, got " + std::to_string(lobes));
    if (parameters.threads < 0)
        throw ArgumentError("threads must be >= 0 (0 = all cores), got " + std::to_string(parameters.threads));
    if (parameters.model == ShadingModel::phong && !parameters.camera.allFinite())
        throw ArgumentError("the camera position must be finite");
    for (const double e : parameters.transmission)
        if (!std::isfinite(e)) throw ArgumentError("the transmission colour must be finite");
}

template <typename Real>
ShadingStats PoseShader::shade_impl(const Eigen::MatrixXd& lighting, const ShadingParameters& parameters,
                                    const PoseBuffers<Real>& buffers) const {
    check_call(lighting, parameters, buffers.lobes_per_vertex);
    if (buffers.vertex_count == 0) return {};
    if (!((buffers.lobe_axes && buffers.lobe_bands) || buffers.lobe_params) || !buffers.normals ||
        !buffers.tangents || !buffers.rgb)
        throw ArgumentError("pose shading needs lobe axes and bands (or lobe parameters), normals, tangents and an output");
    if (parameters.model == ShadingModel::phong && !buffers.positions)
        throw ArgumentError("Phong shading needs vertex positions (local viewer)");

    const std::shared_ptr<const ZonalOperator> op = operator_for(parameters.model, parameters.phong_exponent);
    const PoseShadingSetup<double> setup =
        make_setup(*op, lighting, parameters, buffers.lobes_per_vertex, buffers.visibility != nullptr);
    if constexpr (std::is_same_v<Real, float>) return run_threads(detail::to_float(setup), buffers, parameters.threads);
    else return run_threads(setup, buffers, parameters.threads);
}

PreparedShading PoseShader::prepare(const Eigen::MatrixXd& lighting, const ShadingParameters& parameters, int lobes,
                                    bool want_visibility) const {
    check_call(lighting, parameters, lobes);
    const std::shared_ptr<const ZonalOperator> op = operator_for(parameters.model, parameters.phong_exponent);
    PreparedShading prepared;
    prepared.setup_ = std::make_shared<const PoseShadingSetup<float>>(
        detail::to_float(make_setup(*op, lighting, parameters, lobes, want_visibility)));
    prepared.run_ = range_function<float>(order_);
    prepared.run_block_ = detail::block_function(order_);
    return prepared;
}

std::size_t PreparedShading::shade_block(const PoseBlock& block) const {
    std::size_t invalid = 0;
    if (block.vertex_count) run_block_(*setup_, block, invalid);
    return invalid;
}

std::size_t PreparedShading::shade_range(const PoseBuffers<float>& buffers, std::size_t begin, std::size_t end) const {
    std::size_t invalid = 0;
    if (begin < end) run_(*setup_, buffers, begin, end, invalid);
    return invalid;
}

PoseShadingSetup<double> PoseShader::make_setup(const ZonalOperator& op, const Eigen::MatrixXd& lighting,
                                                const ShadingParameters& parameters, int lobes,
                                                bool want_visibility) const {
    const int coefficients = coefficient_count(order_);
    PoseShadingSetup<double> setup;
    setup.order = order_;
    setup.lobes = lobes;
    setup.model = parameters.model;
    setup.camera = {parameters.camera.x(), parameters.camera.y(), parameters.camera.z()};
    setup.want_visibility = want_visibility;
    for (int a = 0; a < order_; ++a) {
        setup.block_offset[a] = int(setup.blocks.size());
        const Eigen::MatrixXd& block = op.blocks[a];
        for (int i = 0; i < block.rows(); ++i)
            for (int j = 0; j < block.cols(); ++j) setup.blocks.push_back(block(i, j));
    }
    // Both lists are sorted by row (then column): pad every row of band l
    // to quarter_turn_width(l) entries (zeros pointing at the band's first
    // coefficient).
    const auto pad_rows = [this](const std::vector<SparseEntry>& entries, std::vector<int>& columns,
                                 std::vector<double>& values) {
        std::size_t e = 0;
        for (int l = 0; l < order_; ++l)
            for (int i = l * l; i < (l + 1) * (l + 1); ++i) {
                int stored = 0;
                for (; e < entries.size() && entries[e].row == i; ++e, ++stored) {
                    columns.push_back(entries[e].column);
                    values.push_back(entries[e].value);
                }
                for (; stored < detail::quarter_turn_width(l); ++stored) {
                    columns.push_back(l * l);
                    values.push_back(0.0);
                }
            }
    };
    pad_rows(quarter_turn_, setup.x_columns, setup.x_values);
    pad_rows(quarter_turn_transposed_, setup.xt_columns, setup.xt_values);
    const LegendreRecurrence& legendre = legendre_recurrence();
    setup.legendre_diagonal = legendre.diagonal;
    setup.legendre_first = legendre.first;
    setup.legendre_a = legendre.a;
    setup.legendre_b = legendre.b;
    setup.lighting.resize(coefficients);
    setup.back.resize(coefficients);
    for (int l = 0; l < order_; ++l) {
        const double zh_scale = std::sqrt(4.0 * std::numbers::pi / (2.0 * l + 1.0));
        setup.zh_scale[l] = zh_scale;
        setup.ao_weight[l] = std::sqrt(4.0 * std::numbers::pi) * diffuse_->blocks[0](0, l);
        // y_lm(−n) = (−1)^l y_lm(n).
        const double back_scale = ((l % 2) ? -1.0 : 1.0) * zh_scale * cosine_zonal_[l];
        for (int m = -l; m <= l; ++m) {
            const int i = sh_index(l, m);
            for (int c = 0; c < 3; ++c) {
                setup.lighting[i][c] = lighting(i, c);
                setup.back[i][c] = parameters.transmission[c] * back_scale * lighting(i, c);
            }
        }
    }
    return setup;
}

template <typename Real>
ShadingStats PoseShader::run_threads(const PoseShadingSetup<Real>& setup, const PoseBuffers<Real>& buffers,
                                     int thread_count) {
    // Blocks of kBlock vertices, a multiple of every target's lanes (1–8),
    // large enough that scheduling one (~1 µs) is lost in its ~0.1 ms of
    // shading.
    constexpr std::size_t kBlock = 2048;
    const detail::RangeFunction<Real> run = range_function<Real>(setup.order);
    std::vector<std::size_t> invalid(block_count(buffers.vertex_count, kBlock), 0);
    parallel_blocks(buffers.vertex_count, {thread_count, kBlock, "sh.pose_shading"},
                    [&](std::size_t block, std::size_t begin, std::size_t end) {
                        run(setup, buffers, begin, end, invalid[block]);
                    });
    ShadingStats stats;
    for (const std::size_t count : invalid) stats.invalid_vertices += count;
    return stats;
}

ShadingStats PoseShader::shade(const Eigen::MatrixXd& lighting, const ShadingParameters& parameters,
                               const PoseBuffers<float>& buffers) const {
    return shade_impl(lighting, parameters, buffers);
}

ShadingStats PoseShader::shade(const Eigen::MatrixXd& lighting, const ShadingParameters& parameters,
                               const PoseBuffers<double>& buffers) const {
    return shade_impl(lighting, parameters, buffers);
}

}  // namespace penumbra::sh
