#include "visibility/pose_model.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "visibility/order_limit.hpp"
#include "visibility/vertex_kernels.hpp"
#include "visibility/weight_blocks.hpp"

namespace penumbra::visibility {

void check_pose_model(const PoseModel& m) {
    if (m.order < 1 || m.order > max_sh_order) throw ArgumentError("model SH order out of range");
    if (m.lobes < 1 || m.lobes > max_lobes) throw ArgumentError("model lobe count out of range");
    if (m.features != PoseFeatures::RotationMatrix && m.features != PoseFeatures::RotationVector)
        throw ArgumentError("model pose features unknown");
    const std::size_t d = m.params_per_vertex(), fpj = features_per_joint(m.features);
    if (m.joints.size() > 65535) throw ArgumentError("too many joints");
    if (m.joint_offsets.size() != m.vertex_count + 1) throw ArgumentError("model joint offsets do not match its vertex count");
    if (m.joint_offsets.front() != 0 || m.joint_offsets.back() != m.joint_index.size())
        throw ArgumentError("model joint offsets are inconsistent");
    for (std::size_t v = 0; v < m.vertex_count; ++v)
        if (m.joint_offsets[v + 1] < m.joint_offsets[v]) throw ArgumentError("model joint offsets decrease");
    for (auto j : m.joint_index)
        if (j >= m.joints.size()) throw ArgumentError("model joint index out of range");
    if (m.bias.size() != m.vertex_count * d) throw ArgumentError("model bias size does not match");
    if (m.feature_offsets.size() != m.joints.size() + 1 || m.feature_offsets.front() != 0)
        throw ArgumentError("model joint feature offsets do not match its joints");
    for (std::size_t j = 0; j < m.joints.size(); ++j)
        if (m.feature_offsets[j + 1] < m.feature_offsets[j] || m.feature_offsets[j + 1] - m.feature_offsets[j] > fpj)
            throw ArgumentError("model joint feature counts out of range");
    if (m.feature_basis.size() != std::size_t(m.feature_offsets.back()) * fpj)
        throw ArgumentError("model joint feature basis size does not match");
    for (float x : m.feature_basis)
        if (!std::isfinite(x)) throw ArgumentError("model has a non-finite value");
    if (m.weight_offsets.size() != m.vertex_count + 1 || m.weight_offsets.front() != 0)
        throw ArgumentError("model weight offsets do not match its vertex count");
    if (m.block_directions.size() != m.joint_index.size()) throw ArgumentError("model block directions do not match");
    for (std::size_t e = 0; e < m.joint_index.size(); ++e)
        if (m.block_directions[e] == 0 || m.block_directions[e] > m.joint_feature_count(m.joint_index[e]))
            throw ArgumentError("model block directions out of range");
    for (std::size_t v = 0; v < m.vertex_count; ++v) {
        std::uint64_t size = 0;
        for (std::uint32_t e = m.joint_offsets[v]; e < m.joint_offsets[v + 1]; ++e)
            size += std::uint64_t(m.block_directions[e]) * d;
        if (m.weight_offsets[v + 1] != m.weight_offsets[v] + size) throw ArgumentError("model weight offsets are inconsistent");
    }
    if (m.weights.size() != m.weight_offsets.back()) throw ArgumentError("model weight size does not match");
    if (m.weight_scales.size() != m.joint_index.size()) throw ArgumentError("model weight scales do not match");
    for (float x : m.bias)
        if (!std::isfinite(x)) throw ArgumentError("model has a non-finite value");
    for (float x : m.weight_scales)
        if (!std::isfinite(x) || x < 0.0f) throw ArgumentError("model has a non-finite or negative weight scale");
    for (std::uint16_t x : m.weights)
        if (!finite_half(x)) throw ArgumentError("model has a non-finite value");
}

void use_raw_joint_features(PoseModel& model) {
    const std::size_t fpj = std::size_t(features_per_joint(model.features)), J = model.joints.size();
    model.feature_offsets.resize(J + 1);
    for (std::size_t j = 0; j <= J; ++j) model.feature_offsets[j] = std::uint32_t(j * fpj);
    model.feature_basis.assign(J * fpj * fpj, 0.0f);
    for (std::size_t r = 0; r < J * fpj; ++r) model.feature_basis[r * fpj + r % fpj] = 1.0f;
    model.block_directions.assign(model.joint_index.size(), std::uint8_t(fpj));
}

void index_weight_blocks(PoseModel& model) {
    const std::size_t d = std::size_t(model.params_per_vertex()), V = model.vertex_count;
    if (model.joint_offsets.size() != V + 1) throw ArgumentError("model joint offsets do not match its vertex count");
    if (model.feature_offsets.size() != model.joints.size() + 1)
        throw ArgumentError("model joint feature offsets do not match its joints");
    model.weight_offsets.assign(V + 1, 0);
    for (std::size_t v = 0; v < V; ++v) {
        if (model.joint_offsets[v + 1] < model.joint_offsets[v]) throw ArgumentError("model joint offsets decrease");
        std::uint64_t at = model.weight_offsets[v];
        for (std::uint32_t e = model.joint_offsets[v]; e < model.joint_offsets[v + 1]; ++e) {
            if (e >= model.joint_index.size() || model.joint_index[e] >= model.joints.size())
                throw ArgumentError("model joint index out of range");
            if (e >= model.block_directions.size() || model.block_directions[e] == 0 ||
                model.block_directions[e] > model.joint_feature_count(model.joint_index[e]))
                throw ArgumentError("model block directions out of range");
            at += std::uint64_t(model.block_directions[e]) * d;
        }
        model.weight_offsets[v + 1] = at;
    }
}

void set_weights(PoseModel& model, const std::vector<float>& weights) {
    index_weight_blocks(model);
    const std::size_t d = std::size_t(model.params_per_vertex());
    if (weights.size() != model.weight_offsets.back()) throw ArgumentError("model weight size does not match");
    model.weight_scales.resize(model.joint_index.size());
    model.weights.resize(weights.size());
    std::size_t at = 0;
    for (std::size_t e = 0; e < model.joint_index.size(); ++e) {
        const std::size_t size = std::size_t(model.block_directions[e]) * d;
        model.weight_scales[e] = pack_weight_block(weights.data() + at, size, model.weights.data() + at);
        at += size;
    }
}

std::vector<float> weight_values(const PoseModel& model) {
    const std::size_t d = std::size_t(model.params_per_vertex());
    std::vector<float> values(model.weights.size());
    std::size_t at = 0;
    for (std::size_t e = 0; e < model.weight_scales.size() && e < model.block_directions.size(); ++e) {
        const std::size_t size = std::size_t(model.block_directions[e]) * d;
        if (at + size > values.size()) break;
        unpack_weight_block(model.weights.data() + at, size, model.weight_scales[e], values.data() + at);
        at += size;
    }
    return values;
}

void synthesize_params(const PoseModel& model, const float* joint_rotations, float* params_out, int threads) {
    synthesize_lobes(model, joint_rotations, params_out, nullptr, nullptr, threads);
}

std::vector<float> pose_features(const PoseModel& model, const float* joint_rotations) {
    const int fpj = features_per_joint(model.features);
    std::vector<float> out(model.feature_offsets.back());
    for (std::size_t j = 0; j < model.joints.size(); ++j) {
        for (int k = 0; k < 9; ++k)
            if (!std::isfinite(joint_rotations[9 * j + k]))
                throw ArgumentError("joint rotation of '" + model.joints[j] + "' is not finite");
        double phi[9];
        joint_features(model.features, joint_rotations + 9 * j, phi);
        // Projected on the joint's directions in double; single precision
        // after, like the stored weights and the output: at most a few dozen
        // products per parameter, and the loop vectorizes.
        for (std::uint32_t r = model.feature_offsets[j]; r < model.feature_offsets[j + 1]; ++r) {
            double z = 0.0;
            for (int a = 0; a < fpj; ++a) z += double(model.feature_basis[std::size_t(r) * fpj + a]) * phi[a];
            out[r] = float(z);
        }
    }
    return out;
}

namespace {

detail::PoseBlocks pose_blocks(const PoseModel& model) {
    return {model.params_per_vertex(), model.feature_offsets.data(), model.joint_offsets.data(),
            model.joint_index.data(),  model.block_directions.data(), model.weight_offsets.data(),
            model.bias.data(),         model.weights.data(),          model.weight_scales.data()};
}

}  // namespace

void synthesize_params_range(const PoseModel& model, const float* features, std::size_t begin, std::size_t end,
                             float* params_out) {
    // A vertex the model stores as constant has no joint blocks: its
    // parameters are the bias alone. The loop is vertex_kernels.cpp's (SIMD
    // targets chosen at run time).
    detail::apply_pose_blocks(pose_blocks(model), features, begin, end, params_out);
}

void synthesize_rows(const PoseModel& model, const float* features, std::size_t begin, std::size_t end,
                     float* params_out, std::size_t stride) {
    detail::apply_pose_blocks(pose_blocks(model), features, begin, end, params_out, std::max<std::size_t>(stride, 1));
}

void synthesize_lobes(const PoseModel& model, const float* joint_rotations, float* params_out, float* axes_out,
                      float* bands_out, int threads) {
    const int d = model.params_per_vertex();
    const std::vector<float> features = pose_features(model, joint_rotations);
    parallel_for(model.vertex_count, {threads, 2048, "visibility.pose_lobes"}, [&](std::size_t begin, std::size_t end) {
        synthesize_params_range(model, features.data(), begin, end, params_out + begin * d);
        if (axes_out && bands_out)
            lobes_from_params(model.order, model.lobes, end - begin, params_out + begin * d,
                              axes_out + begin * model.lobes * 3, bands_out + begin * model.lobes * model.order);
    });
}

void lobes_from_params(int order, int lobes, std::size_t vertex_count, const float* params, float* axes_out,
                       float* bands_out) {
    // lambert_to_axis (zh_fit.hpp) in float SIMD lanes (vertex_kernels.cpp).
    detail::lobes_from_params(order, vertex_count * std::size_t(lobes), params, axes_out, bands_out);
}

}  // namespace penumbra::visibility
