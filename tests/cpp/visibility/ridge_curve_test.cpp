// The held-out error curve of the ridge model in closed form
// (visibility/ridge_curve.hpp) against the same error computed directly:
// predict every held-out frame for λ, map each vertex's parameter error
// through the Jacobian of Eq. 1, sum.
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "visibility/ridge_curve.hpp"
#include "visibility/zh_fit.hpp"

namespace penumbra::visibility {
namespace {

// J of Eq. 1 at params by central differences (not the code's forward ones).
Eigen::MatrixXd jacobian(int order, int lobes, const Eigen::VectorXd& params) {
    const int n_sh = order * order, d = int(params.size());
    Eigen::MatrixXd J(n_sh, d);
    std::vector<double> up(n_sh), down(n_sh);
    for (int i = 0; i < d; ++i) {
        Eigen::VectorXd p = params;
        p[i] += 1e-5;
        lobes_to_sh(order, lobes, p.data(), up.data());
        p[i] -= 2e-5;
        lobes_to_sh(order, lobes, p.data(), down.data());
        for (int k = 0; k < n_sh; ++k) J(k, i) = (up[k] - down[k]) / 2e-5;
    }
    return J;
}

TEST(RidgeCurve, closed_form_equals_the_error_of_each_prediction) {
    const int order = 4, lobes = 2, d = lobes * params_per_lobe(order), V = 7, H = 5, r = 6;
    std::mt19937 rng(3);
    std::normal_distribution<double> normal(0.0, 1.0);
    const auto random = [&](Eigen::Index rows, Eigen::Index cols, double scale) {
        Eigen::MatrixXd m(rows, cols);
        for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = scale * normal(rng);
        return m;
    };
    // Mean lobes inside the Lambert disc (|(X, Y)| < 2), bands of either sign.
    const Eigen::RowVectorXf mean = random(1, V * d, 0.5).cast<float>();
    const Eigen::MatrixXd P = random(H, r, 1.0);
    const Eigen::MatrixXf C = random(r, V * d, 0.3).cast<float>(), R = random(H, V * d, 0.2).cast<float>();
    const RidgeCurve curve = ridge_curve(order, lobes, mean, P, C, R, 2);
    EXPECT_EQ(curve.samples, std::size_t(V * H));
    for (double scale : {0.0, 0.01, 0.3, 1.0, 7.0}) {
        const Eigen::VectorXd w = Eigen::VectorXd::LinSpaced(r, 1.0, 0.1) * scale;
        const Eigen::MatrixXd error = R.cast<double>() - P * w.asDiagonal() * C.cast<double>();
        double sum = 0.0;
        for (int v = 0; v < V; ++v) {
            const Eigen::MatrixXd J = jacobian(order, lobes, mean.segment(v * d, d).cast<double>().transpose());
            sum += (error.middleCols(v * d, d) * J.transpose()).squaredNorm() / (4.0 * std::numbers::pi);
        }
        const double expected = std::sqrt(sum / (V * H));
        EXPECT_NEAR(curve.rms(w), expected, 1e-4 * expected + 1e-9) << "scale " << scale;
    }
}

TEST(RidgeCurve, no_vertices_or_no_held_out_frames_give_zero) {
    const RidgeCurve none = ridge_curve(4, 2, Eigen::RowVectorXf(0), Eigen::MatrixXd::Zero(3, 2), Eigen::MatrixXf(2, 0),
                                        Eigen::MatrixXf(3, 0));
    EXPECT_EQ(none.rms(Eigen::VectorXd::Ones(2)), 0.0);
}

}  // namespace
}  // namespace penumbra::visibility
