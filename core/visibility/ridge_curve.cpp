#include "visibility/ridge_curve.hpp"

#include <cmath>
#include <numbers>
#include <vector>

#include "common/parallel.hpp"
#include "visibility/zh_fit.hpp"

namespace penumbra::visibility {

namespace {

// J / sqrt(4π) (order² × d) of Eq. 1 at params, by forward differences: the
// map is smooth away from the Lambert disc's rim, and the curve only ranks λ.
Eigen::MatrixXd scaled_jacobian(int order, int lobes, const double* params) {
    const int n_sh = order * order, d = lobes * params_per_lobe(order);
    constexpr double step = 1e-6;
    std::vector<double> p(params, params + d), base(n_sh), moved(n_sh);
    lobes_to_sh(order, lobes, p.data(), base.data());
    Eigen::MatrixXd J(n_sh, d);
    const double scale = 1.0 / std::sqrt(4.0 * std::numbers::pi);
    for (int i = 0; i < d; ++i) {
        p[i] = params[i] + step;
        lobes_to_sh(order, lobes, p.data(), moved.data());
        p[i] = params[i];
        for (int k = 0; k < n_sh; ++k) J(k, i) = scale * (moved[k] - base[k]) / step;
    }
    return J;
}

// Partial sums of one block of vertices.
struct Sums {
    double residual_squared = 0.0;
    Eigen::MatrixXd cc, rc;  // C' C'ᵀ (r × r) and R' C'ᵀ (H × r), primes: through J
};

}  // namespace

double RidgeCurve::rms(const Eigen::VectorXd& w) const {
    const double sum = residual_squared - 2.0 * w.dot(g) + w.dot(q * w);
    return samples ? std::sqrt(std::max(sum, 0.0) / double(samples)) : 0.0;
}

RidgeCurve ridge_curve(int order, int lobes, const Eigen::RowVectorXf& mean_params, const Eigen::MatrixXd& P,
                       const Eigen::MatrixXf& C, const Eigen::MatrixXf& R, int threads) {
    const int d = lobes * params_per_lobe(order);
    const std::size_t V = std::size_t(mean_params.size()) / d;
    const Eigen::Index r = C.rows(), H = R.rows();
    const std::size_t block = 256;
    std::vector<Sums> sums(block_count(V, block), Sums{0.0, Eigen::MatrixXd::Zero(r, r), Eigen::MatrixXd::Zero(H, r)});
    parallel_blocks(V, {threads, block, "visibility.ridge_curve"}, [&](std::size_t b, std::size_t begin,
                                                                      std::size_t end) {
        Sums& s = sums[b];
        Eigen::VectorXd mean(d);
        for (std::size_t v = begin; v < end; ++v) {
            for (int i = 0; i < d; ++i) mean[i] = mean_params[Eigen::Index(v * d + i)];
            const Eigen::MatrixXd J = scaled_jacobian(order, lobes, mean.data());
            const Eigen::MatrixXd c = C.middleCols(Eigen::Index(v * d), d).cast<double>() * J.transpose();
            const Eigen::MatrixXd res = R.middleCols(Eigen::Index(v * d), d).cast<double>() * J.transpose();
            s.cc.noalias() += c * c.transpose();
            s.rc.noalias() += res * c.transpose();
            s.residual_squared += res.squaredNorm();
        }
    });
    // Summed in block order: the same answer on any number of threads.
    Sums total{0.0, Eigen::MatrixXd::Zero(r, r), Eigen::MatrixXd::Zero(H, r)};
    for (const Sums& s : sums) {
        total.residual_squared += s.residual_squared;
        total.cc += s.cc;
        total.rc += s.rc;
    }
    RidgeCurve curve;
    curve.residual_squared = total.residual_squared;
    curve.g = (P.array() * total.rc.array()).colwise().sum().transpose();
    curve.q = (P.transpose() * P).cwiseProduct(total.cc);
    curve.samples = V * std::size_t(H);
    return curve;
}

}  // namespace penumbra::visibility
