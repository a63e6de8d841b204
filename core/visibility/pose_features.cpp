#include "visibility/pose_features.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>
#include <Eigen/SVD>

namespace penumbra::visibility {

namespace {

Eigen::Matrix3d to_matrix(const float* r) {
    Eigen::Matrix3d m;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) m(i, j) = r[3 * i + j];
    return m;
}

}  // namespace

int features_per_joint(PoseFeatures features) { return features == PoseFeatures::RotationVector ? 3 : 9; }

void joint_features(PoseFeatures features, const float* rotation, double* out) {
    if (features == PoseFeatures::RotationVector) {
        const Eigen::AngleAxisd aa(to_matrix(rotation));
        const Eigen::Vector3d v = aa.axis() * aa.angle();
        for (int k = 0; k < 3; ++k) out[k] = v[k];
    } else {
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) out[3 * i + j] = double(rotation[3 * i + j]) - (i == j ? 1.0 : 0.0);
    }
}

double rotation_angle_between(const float* a, const float* b) {
    const Eigen::Matrix3d r = to_matrix(a).transpose() * to_matrix(b);
    const double c = std::clamp((r.trace() - 1.0) / 2.0, -1.0, 1.0);
    return std::acos(c);
}

Eigen::MatrixXd raw_pose_matrix(const TrainingSet& set, const std::vector<std::size_t>& bones, PoseFeatures features) {
    const int fpj = features_per_joint(features);
    Eigen::MatrixXd raw(set.frames.size(), bones.size() * fpj);
    for (std::size_t f = 0; f < set.frames.size(); ++f)
        for (std::size_t j = 0; j < bones.size(); ++j) {
            double phi[9];
            joint_features(features, set.frames[f].bone_rotations.data() + 9 * bones[j], phi);
            for (int a = 0; a < fpj; ++a) raw(f, j * fpj + a) = phi[a];
        }
    return raw;
}

FeatureDirections principal_feature_directions(const Eigen::MatrixXd& raw, const std::vector<std::size_t>& rows,
                                               int fpj, double tolerance) {
    FeatureDirections out;
    out.offsets.assign(1, 0);
    const std::size_t joints = std::size_t(raw.cols()) / std::size_t(fpj);
    for (std::size_t j = 0; j < joints; ++j) {
        Eigen::MatrixXd block(rows.size(), fpj);
        for (std::size_t r = 0; r < rows.size(); ++r) block.row(r) = raw.block(rows[r], j * fpj, 1, fpj);
        block.rowwise() -= block.colwise().mean();
        const Eigen::JacobiSVD<Eigen::MatrixXd> svd(block, Eigen::ComputeFullV);
        const Eigen::VectorXd& sv = svd.singularValues();
        int kept = 0;
        const double largest = sv.size() ? sv[0] : 0.0;
        while (kept < sv.size() && sv[kept] > 1e-12 * largest && sv[kept] >= tolerance * largest) ++kept;
        for (int c = 0; c < kept; ++c)
            for (int a = 0; a < fpj; ++a) out.basis.push_back(float(svd.matrixV()(a, c)));
        out.offsets.push_back(out.offsets.back() + std::uint32_t(kept));
    }
    return out;
}

Eigen::MatrixXd project_pose_matrix(const Eigen::MatrixXd& raw, int fpj, const FeatureDirections& directions) {
    Eigen::MatrixXd A(raw.rows(), Eigen::Index(directions.offsets.back()));
    for (std::size_t j = 0; j + 1 < directions.offsets.size(); ++j) {
        const Eigen::Index first = Eigen::Index(directions.offsets[j]);
        const Eigen::Index count = Eigen::Index(directions.offsets[j + 1] - directions.offsets[j]);
        const Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> basis(
            directions.basis.data() + std::size_t(first) * fpj, count, fpj);
        A.middleCols(first, count) = raw.middleCols(Eigen::Index(j) * fpj, fpj) * basis.cast<double>().transpose();
    }
    return A;
}

}  // namespace penumbra::visibility
