#include "visibility/pose_fit.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <mutex>
#include <numbers>
#include <numeric>
#include <string>
#include <string_view>
#include <utility>

#include <Eigen/SVD>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "visibility/ridge_curve.hpp"
#include "visibility/weight_blocks.hpp"

namespace penumbra::visibility {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Running sums for Errors, merged across threads.
struct ErrorSums {
    double sq = 0.0, ao_abs = 0.0, ao_max = 0.0;
    std::size_t n = 0;
    // One (vertex, frame) pair's terms: |Δv|²/4π and |Δ AO|.
    struct Sample {
        double sq, ao;
    };
    static Sample sample(int order, const double* predicted, const float* truth) {
        double diff[64], d2 = 0.0;
        const int n_sh = order * order;
        for (int i = 0; i < n_sh; ++i) {
            diff[i] = predicted[i] - double(truth[i]);
            d2 += diff[i] * diff[i];
        }
        return {d2 / (4.0 * std::numbers::pi), std::abs(ambient_occlusion(order, diff))};
    }
    void add(const Sample& e) {
        sq += e.sq;
        ao_abs += e.ao;
        ao_max = std::max(ao_max, e.ao);
        ++n;
    }
    void add(int order, const double* predicted, const float* truth) { add(sample(order, predicted, truth)); }
    void merge(const ErrorSums& o) {
        sq += o.sq;
        ao_abs += o.ao_abs;
        ao_max = std::max(ao_max, o.ao_max);
        n += o.n;
    }
    Errors result() const {
        Errors e;
        e.samples = n;
        if (n) {
            e.sh_rms = std::sqrt(sq / double(n));
            e.ao_mean_abs = ao_abs / double(n);
            e.ao_max_abs = ao_max;
        }
        return e;
    }
};

// ρ from 1e-8 to 10, four steps a decade: each costs O(r²) (ridge_curve.hpp).
const std::vector<double>& ridge_grid() {
    static const std::vector<double> grid = [] {
        std::vector<double> g;
        for (int i = 0; i <= 36; ++i) g.push_back(std::pow(10.0, -8.0 + 0.25 * i));
        return g;
    }();
    return grid;
}

void check_fit_settings(const FitSettings& s) {
    check_range("lobes", s.lobes, FitSettings::lobes_range);
    if (s.features != PoseFeatures::RotationMatrix && s.features != PoseFeatures::RotationVector)
        throw ArgumentError("unknown pose features");
    if (!(s.joint_tolerance_degrees >= 0.0)) throw ArgumentError("joint tolerance must be >= 0 degrees");
    if (s.holdout_stride < 0 || s.holdout_stride == 1)
        throw ArgumentError("holdout_stride must be 0 (none) or >= 2");
    if (!(s.constant_tolerance >= 0.0) || !(s.prune_tolerance >= 0.0) || !(s.feature_tolerance >= 0.0 && s.feature_tolerance <= 1.0))
        throw ArgumentError("tolerances must be >= 0 (the feature tolerance at most 1)");
    if (s.zh_iterations < 0 || s.frame_zh_iterations < 0 || !(s.axis_prior >= 0.0)) throw ArgumentError("ZH fit settings out of range");
    check_range("threads", s.threads, threads_range);
}

}  // namespace

std::vector<JointChoice> choose_active_joints(const TrainingSet& set, const std::vector<BoneInfluence>& influence,
                                              double tolerance_degrees) {
    const std::size_t n_bones = set.bone_names.size();
    if (influence.size() != n_bones)
        throw ArgumentError("one bone influence per armature bone is needed (" + std::to_string(n_bones) + "), got " +
                            std::to_string(influence.size()));
    std::vector<JointChoice> out(n_bones);
    for (std::size_t b = 0; b < n_bones; ++b) {
        JointChoice& c = out[b];
        c.name = set.bone_names[b];
        double largest = 0.0;
        for (std::size_t f = 1; f < set.frames.size(); ++f)
            largest = std::max(largest, rotation_angle_between(set.frames[0].bone_rotations.data() + 9 * b,
                                                               set.frames[f].bone_rotations.data() + 9 * b));
        c.max_angle_degrees = largest * 180.0 / std::numbers::pi;
        char angle[64];
        std::snprintf(angle, sizeof angle, "%.3g°", c.max_angle_degrees);
        if (!influence[b].deforms_mesh)
            c.reason = "dropped: deforms no vertex of this mesh (nor do its children)";
        else if (influence[b].rigid_for_whole_mesh)
            c.reason = "dropped: carries the whole mesh rigidly (cannot change self-occlusion)";
        else if (c.max_angle_degrees <= tolerance_degrees)
            c.reason = std::string("dropped: rotates at most ") + angle + " over the training frames";
        else {
            c.active = true;
            c.reason = std::string("kept: rotates up to ") + angle + " and deforms part of the mesh";
        }
    }
    return out;
}

namespace {

// Shapes every step of the fit shares: SH order and count, lobes, d lobe
// parameters per vertex, V vertices, F frames, fpj raw features per joint,
// k pose features (Σ over active joints of the directions kept): joint j's
// are columns [feature_start[j], feature_start[j + 1]) of A.
struct FitShape {
    int order, lobes, n_sh, d, fpj;
    std::size_t V, F, k;
    std::vector<std::size_t> feature_start;

    std::size_t joints() const { return feature_start.empty() ? 0 : feature_start.size() - 1; }
    Eigen::Index first(std::size_t j) const { return Eigen::Index(feature_start[j]); }
    Eigen::Index count(std::size_t j) const { return Eigen::Index(feature_start[j + 1] - feature_start[j]); }
};

// The first frame before f whose visibility of vertex v equals frame f's
// bit for bit (hashes[0..f] hold each frame's hash), or f.
std::size_t earlier_equal(const TrainingSet& set, std::size_t v, int n_sh, std::size_t f,
                          const std::vector<std::uint64_t>& hashes) {
    const float* mine = set.frames[f].visibility.data() + v * n_sh;
    for (std::size_t g = 0; g < f; ++g)
        if (hashes[g] == hashes[f] &&
            std::memcmp(set.frames[g].visibility.data() + v * n_sh, mine, sizeof(float) * n_sh) == 0)
            return g;
    return f;
}

// Step 1 (fig. 2b): ZH lobes per vertex and frame, the rows of B (F × V·d).
// Each vertex's frames are fitted from a reference fit of its mean
// visibility (zh_fit.hpp). Adds the lobes' errors against the baked SH to
// `errors`; progress 0 → 0.8.
Eigen::MatrixXf fit_frame_lobes(const TrainingSet& set, const FitSettings& settings, const FitShape& shape,
                                const Progress& progress, ErrorSums& errors) {
    const int order = shape.order, n_sh = shape.n_sh, d = shape.d;
    const std::size_t F = shape.F;
    Eigen::MatrixXf B(F, shape.V * d);
    std::mutex merge_mutex;
    ZhFitSettings zs;
    zs.order = order;
    zs.lobes = shape.lobes;
    zs.iterations = settings.zh_iterations;
    zs.axis_prior = settings.axis_prior;
    ZhFitSettings zs_frame = zs;
    zs_frame.iterations = settings.frame_zh_iterations;
    parallel_for(shape.V, {settings.threads, 16, "visibility.zh_fit", 0.0, 0.8},
                 [&](std::size_t begin, std::size_t end) {
        ErrorSums local;
        std::vector<double> mean(n_sh), sh(n_sh), ref(d), params(d), fitted(n_sh);
        std::vector<std::uint64_t> hashes(F);
        std::vector<ErrorSums::Sample> samples(F);
        for (std::size_t v = begin; v < end; ++v) {
            std::fill(mean.begin(), mean.end(), 0.0);
            for (const auto& frame : set.frames)
                for (int i = 0; i < n_sh; ++i) mean[i] += frame.visibility[v * n_sh + i];
            for (auto& x : mean) x /= double(F);
            fit_zh_lobes(zs, mean.data(), nullptr, ref.data());
            for (std::size_t f = 0; f < F; ++f) {
                const float* truth = set.frames[f].visibility.data() + v * n_sh;
                // A vertex's visibility repeats exactly whenever no ray changes
                // between two poses (over half the (vertex, frame) pairs of
                // the humanoid at 128 rays): the fit, a function of the SH
                // vector and the reference alone, is then copied, not redone.
                hashes[f] = std::hash<std::string_view>{}(
                    std::string_view(reinterpret_cast<const char*>(truth), sizeof(float) * n_sh));
                const std::size_t same = earlier_equal(set, v, n_sh, f, hashes);
                if (same < f) {  // so are its lobes' errors
                    for (int i = 0; i < d; ++i) B(f, v * d + i) = B(same, v * d + i);
                    samples[f] = samples[same];
                } else {
                    for (int i = 0; i < n_sh; ++i) sh[i] = truth[i];
                    fit_zh_lobes(zs_frame, sh.data(), ref.data(), params.data());
                    for (int i = 0; i < d; ++i) B(f, v * d + i) = float(params[i]);
                    lobes_to_sh(order, shape.lobes, params.data(), fitted.data());
                    samples[f] = ErrorSums::sample(order, fitted.data(), truth);
                }
                local.add(samples[f]);
            }
        }
        std::lock_guard<std::mutex> lock(merge_mutex);
        errors.merge(local);
    }, progress);
    return B;
}

// left · right for a wide right (V·d columns), its columns split across
// threads: Eigen's product alone runs on one.
Eigen::MatrixXf wide_product(const Eigen::MatrixXf& left, const Eigen::MatrixXf& right, int threads) {
    Eigen::MatrixXf out(left.rows(), right.cols());
    parallel_for(std::size_t(right.cols()), {threads, 4096, "visibility.wide_product"}, [&](std::size_t begin,
                                                                                           std::size_t end) {
        const Eigen::Index b = Eigen::Index(begin), n = Eigen::Index(end - begin);
        out.middleCols(b, n).noalias() = left * right.middleCols(b, n);
    });
    return out;
}

// The ridge solution's pieces for a subset of frames: feature and lobe
// parameter means, and the centred SVD A_c = U S Vᵀ with Uᵀ·B_c.
struct RidgeSolver {
    Eigen::VectorXd feature_mean, s;
    Eigen::MatrixXd V;
    Eigen::MatrixXf ut_b;
    Eigen::RowVectorXf b_mean;

    // s/(s² + λ) per singular value, λ = ρ·s_max²; 0 for s <= 1e-12·s_max.
    Eigen::VectorXd shrink(double rho) const {
        const double smax = s.size() ? s[0] : 0.0;
        const double lambda = rho * smax * smax;
        Eigen::VectorXd w(s.size());
        for (Eigen::Index i = 0; i < s.size(); ++i)
            w[i] = s[i] > 1e-12 * smax ? s[i] / (s[i] * s[i] + lambda) : 0.0;
        return w;
    }
    // W = V·diag(s/(s²+λ))·Uᵀ·B_c (k × V·d).
    Eigen::MatrixXf weights(double rho, int threads) const {
        return wide_product((V * shrink(rho).asDiagonal()).cast<float>(), ut_b, threads);
    }
};

// One joint block of a vertex: the joint and how many of its leading
// feature directions the vertex keeps.
struct KeptBlock {
    std::uint16_t joint;
    std::uint8_t directions;
};
using KeptBlocks = std::vector<std::vector<KeptBlock>>;

// A model as stored, per vertex: the blocks kept (none: a constant vertex)
// and the bias with the feature means folded in.
struct PrunedModel {
    KeptBlocks kept;
    std::vector<float> bias;
};

// Steps 2–3: the linear model on top of the ZH lobes B and the pose matrix A.
class LinearFit {
public:
    LinearFit(const TrainingSet& set, const FitSettings& settings, const FitShape& shape, const Eigen::MatrixXd& A,
              const Eigen::MatrixXf& B)
        : set_(set), settings_(settings), shape_(shape), A_(A), B_(B) {}

    RidgeSolver solver(const std::vector<std::size_t>& rows) const;
    // Errors of lobe parameters predicted for `rows` (rows.size() × V·d) against their baked SH.
    Errors predicted_errors(const std::vector<std::size_t>& rows, const Eigen::MatrixXf& predicted) const;
    // Per vertex: constant, or the joint directions that matter (decided on `rows`,
    // the frames the solver was fitted on, with W itself), and the bias. W: the solver's ridge weights (k × V·d); the blocks kept are
    // rounded in place to their stored form (weight_blocks.hpp) before the
    // bias is folded, so the bias absorbs the rounding at the mean pose and
    // errors measured with W afterwards are the stored model's.
    PrunedModel prune(const std::vector<std::size_t>& rows, const RidgeSolver& sol, Eigen::MatrixXf& W,
                      const Progress& progress, double from, double to) const;
    // Errors of a pruned model (as stored) on frames it was not fitted on.
    Errors pruned_errors(const PrunedModel& pruned, const Eigen::MatrixXf& W,
                         const std::vector<std::size_t>& rows) const;

private:
    // Scratch of one pruning worker.
    struct PruneScratch {
        Eigen::MatrixXd dropped, trial;
        std::vector<Eigen::MatrixXd> parts;  // per pose feature (joint direction)
        std::vector<double> norms;
        std::vector<int> directions;         // per joint, kept so far
    };
    void prune_vertex(std::size_t v, const std::vector<std::size_t>& rows, const RidgeSolver& sol,
                      const Eigen::MatrixXf& W, const Eigen::MatrixXd& Ac, PruneScratch& scratch,
                      std::vector<KeptBlock>& keep) const;

    const TrainingSet& set_;
    const FitSettings& settings_;
    const FitShape& shape_;
    const Eigen::MatrixXd& A_;
    const Eigen::MatrixXf& B_;
};

RidgeSolver LinearFit::solver(const std::vector<std::size_t>& rows) const {
    const std::size_t k = shape_.k;
    RidgeSolver sol;
    // Gathered column by column (B is column-major, F × V·d): a row at a time
    // would stride through all of it once per frame.
    Eigen::MatrixXd a = A_(rows, Eigen::all);
    Eigen::MatrixXf b = B_(rows, Eigen::all);
    sol.feature_mean = a.colwise().mean().transpose();
    sol.b_mean = b.colwise().mean();
    if (k == 0) return sol;
    a.rowwise() -= sol.feature_mean.transpose();
    b.rowwise() -= sol.b_mean;
    // JacobiSVD: BDCSVD (Eigen 3.4) returned NaN now and then on the exactly
    // zero columns that unmoving feature entries leave.
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
    sol.s = svd.singularValues();
    sol.V = svd.matrixV();
    sol.ut_b = wide_product(svd.matrixU().transpose().cast<float>(), b, settings_.threads);
    return sol;
}

Errors LinearFit::predicted_errors(const std::vector<std::size_t>& rows, const Eigen::MatrixXf& predicted) const {
    const int order = shape_.order, n_sh = shape_.n_sh, d = shape_.d;
    ErrorSums total;
    std::mutex merge_mutex;
    parallel_for(shape_.V, {settings_.threads, 256, "visibility.model_errors"}, [&](std::size_t begin,
                                                                                   std::size_t end) {
        ErrorSums local;
        std::vector<double> params(d), sh(n_sh);
        for (std::size_t v = begin; v < end; ++v)
            for (std::size_t r = 0; r < rows.size(); ++r) {
                for (int i = 0; i < d; ++i) params[i] = predicted(r, v * d + i);
                lobes_to_sh(order, shape_.lobes, params.data(), sh.data());
                local.add(order, sh.data(), set_.frames[rows[r]].visibility.data() + v * n_sh);
            }
        std::lock_guard<std::mutex> lock(merge_mutex);
        total.merge(local);
    });
    return total.result();
}

// One vertex: constant when its parameters vary less than
// constant_tolerance (RMS); otherwise the contributions of its joints'
// feature directions are dropped, smallest first, while the dropped part
// stays under prune_tolerance. A joint's directions go from its last (the
// least moving) to its first, so what a vertex keeps of a joint is always
// its leading directions (a block of the stored model): each step drops the
// smallest of the joints' last kept parts.
void LinearFit::prune_vertex(std::size_t v, const std::vector<std::size_t>& rows, const RidgeSolver& sol,
                             const Eigen::MatrixXf& W, const Eigen::MatrixXd& Ac, PruneScratch& scratch,
                             std::vector<KeptBlock>& keep) const {
    const std::size_t R = rows.size(), n_active = shape_.joints();
    const int d = shape_.d;
    const Eigen::RowVectorXd mean = sol.b_mean.segment(v * d, d).cast<double>();
    double variation = 0.0;
    for (std::size_t r = 0; r < R; ++r)
        for (int i = 0; i < d; ++i) variation += std::pow(double(B_(rows[r], v * d + i)) - mean[i], 2);
    variation = std::sqrt(variation / double(R * d));
    if (!shape_.k || variation <= settings_.constant_tolerance) return;
    const Eigen::MatrixXd Wv = W.middleCols(v * d, d).cast<double>();
    for (std::size_t c = 0; c < shape_.k; ++c) {
        scratch.parts[c].noalias() = Ac.col(Eigen::Index(c)) * Wv.row(Eigen::Index(c));
        scratch.norms[c] = scratch.parts[c].squaredNorm();
    }
    for (std::size_t j = 0; j < n_active; ++j) scratch.directions[j] = int(shape_.count(j));
    scratch.dropped.setZero();
    for (;;) {
        std::size_t best = n_active;
        double best_norm = std::numeric_limits<double>::infinity();
        for (std::size_t j = 0; j < n_active; ++j) {
            if (scratch.directions[j] == 0) continue;
            const double norm = scratch.norms[std::size_t(shape_.first(j)) + scratch.directions[j] - 1];
            if (norm < best_norm) {
                best_norm = norm;
                best = j;
            }
        }
        if (best == n_active) break;
        scratch.trial = scratch.dropped + scratch.parts[std::size_t(shape_.first(best)) + scratch.directions[best] - 1];
        if (std::sqrt(scratch.trial.squaredNorm() / double(R * d)) > settings_.prune_tolerance) break;
        scratch.dropped = scratch.trial;
        --scratch.directions[best];
    }
    for (std::size_t j = 0; j < n_active; ++j)
        if (scratch.directions[j] > 0) keep.push_back({std::uint16_t(j), std::uint8_t(scratch.directions[j])});
}

PrunedModel LinearFit::prune(const std::vector<std::size_t>& rows, const RidgeSolver& sol, Eigen::MatrixXf& W,
                             const Progress& progress, double from, double to) const {
    const std::size_t R = rows.size(), n_active = shape_.joints();
    const int d = shape_.d;
    PrunedModel out;
    out.kept = KeptBlocks(shape_.V);
    out.bias.assign(shape_.V * d, 0.0f);
    Eigen::MatrixXd Ac(R, shape_.k);
    for (std::size_t r = 0; r < R; ++r) Ac.row(r) = A_.row(rows[r]);
    if (shape_.k) Ac.rowwise() -= sol.feature_mean.transpose();
    parallel_for(shape_.V, {settings_.threads, 64, "visibility.prune", from, to}, [&](std::size_t begin,
                                                                                     std::size_t end) {
        PruneScratch scratch{Eigen::MatrixXd(R, d), Eigen::MatrixXd(R, d),
                             std::vector<Eigen::MatrixXd>(shape_.k, Eigen::MatrixXd(R, d)),
                             std::vector<double>(shape_.k), std::vector<int>(n_active)};
        std::vector<float> block(std::size_t(shape_.fpj) * d);
        for (std::size_t v = begin; v < end; ++v) {
            prune_vertex(v, rows, sol, W, Ac, scratch, out.kept[v]);
            for (const KeptBlock& b : out.kept[v]) {  // columns of vertex v only: no other task touches them
                const Eigen::Index m = b.directions;
                auto stored = W.block(shape_.first(b.joint), v * d, m, d);
                Eigen::Map<Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> copy(block.data(), m, d);
                copy = stored;
                round_weight_block(block.data(), std::size_t(m) * d);
                stored = copy;
            }
            // Bias with the feature means folded in: params = bias + Σ φ_j W_j.
            Eigen::RowVectorXd bias = sol.b_mean.segment(v * d, d).cast<double>();
            for (const KeptBlock& b : out.kept[v])
                bias -= sol.feature_mean.segment(shape_.first(b.joint), b.directions).transpose() *
                        W.block(shape_.first(b.joint), v * d, b.directions, d).cast<double>();
            for (int i = 0; i < d; ++i) out.bias[v * d + i] = float(bias[i]);
        }
    }, progress);
    return out;
}

Errors LinearFit::pruned_errors(const PrunedModel& pruned, const Eigen::MatrixXf& W,
                                const std::vector<std::size_t>& rows) const {
    const int order = shape_.order, n_sh = shape_.n_sh, d = shape_.d;
    const Eigen::Index R = Eigen::Index(rows.size());
    Eigen::MatrixXd features(R, shape_.k);
    for (Eigen::Index r = 0; r < R; ++r) features.row(r) = A_.row(rows[r]);
    ErrorSums total;
    std::mutex merge_mutex;
    parallel_for(shape_.V, {settings_.threads, 256, "visibility.pruned_errors"}, [&](std::size_t begin,
                                                                                    std::size_t end) {
        ErrorSums local;
        Eigen::MatrixXd params(R, d);
        std::vector<double> row(d), sh(n_sh);
        for (std::size_t v = begin; v < end; ++v) {
            // params = bias + Σ over kept joints φ_j W_j, every row at once.
            for (int i = 0; i < d; ++i) params.col(i).setConstant(pruned.bias[v * d + i]);
            for (const KeptBlock& b : pruned.kept[v])
                params.noalias() += features.middleCols(shape_.first(b.joint), b.directions) *
                                    W.block(shape_.first(b.joint), Eigen::Index(v * d), b.directions, d).cast<double>();
            for (Eigen::Index r = 0; r < R; ++r) {
                for (int i = 0; i < d; ++i) row[i] = params(r, i);
                lobes_to_sh(order, shape_.lobes, row.data(), sh.data());
                local.add(order, sh.data(), set_.frames[rows[r]].visibility.data() + v * n_sh);
            }
        }
        std::lock_guard<std::mutex> lock(merge_mutex);
        total.merge(local);
    });
    return total.result();
}

// Held-out frames: every stride-th, when there are at least two strides of
// frames; the rest train.
void split_frames(std::size_t F, int stride, std::vector<std::size_t>& train, std::vector<std::size_t>& holdout) {
    const bool use_holdout = stride >= 2 && F >= std::size_t(2 * stride);
    for (std::size_t f = 0; f < F; ++f)
        (use_holdout && f % stride == std::size_t(stride - 1) ? holdout : train).push_back(f);
}

// Chooses ρ (λ = ρ·s_max²) from ridge_grid by the linearized held-out SH
// error, every ρ from one SVD (ridge_curve.hpp); then measures through SH,
// on the held-out frames, the ridge solution at that ρ and the model as
// stored (ridge, constant vertices, per-vertex joint pruning), both fitted
// without them: the stored model's recipe, its pruning decided on the
// training frames alone. Without held-out frames ρ = 1e-4. Progress 0.8 → 0.9.
double choose_ridge(const LinearFit& fit, const Eigen::MatrixXd& A, const Eigen::MatrixXf& B, const FitShape& shape,
                    const std::vector<std::size_t>& train, const std::vector<std::size_t>& holdout, int threads,
                    const Progress& progress, FitReport& report) {
    double rho = 1e-4;
    if (holdout.empty()) return rho;
    const std::size_t k = shape.k, H = holdout.size();
    const RidgeSolver sol = fit.solver(train);
    Eigen::MatrixXd p(H, k);
    Eigen::MatrixXf residual(H, B.cols());
    for (std::size_t r = 0; r < H; ++r) {
        p.row(r) = A.row(holdout[r]) - sol.feature_mean.transpose();
        residual.row(r) = B.row(holdout[r]) - sol.b_mean;
    }
    const Eigen::MatrixXd pv = k ? Eigen::MatrixXd(p * sol.V) : Eigen::MatrixXd(H, 0);
    if (k) {
        const RidgeCurve curve = ridge_curve(shape.order, shape.lobes, sol.b_mean, pv, sol.ut_b, residual, threads);
        double best = std::numeric_limits<double>::infinity();
        for (double g : ridge_grid()) {
            const double e = curve.rms(sol.shrink(g));
            report.ridge_curve.emplace_back(g, e);
            if (e < best) {
                best = e;
                rho = g;
            }
        }
    }
    progress.report(0.82);
    Eigen::MatrixXf predicted = sol.b_mean.replicate(H, 1);
    if (k) predicted += wide_product((pv * sol.shrink(rho).asDiagonal()).cast<float>(), sol.ut_b, threads);
    report.model_holdout_unpruned = fit.predicted_errors(holdout, predicted);
    Eigen::MatrixXf W_train;
    if (k) W_train = sol.weights(rho, threads);
    const PrunedModel pruned_train = fit.prune(train, sol, W_train, progress, 0.85, 0.9);
    report.model_holdout = fit.pruned_errors(pruned_train, W_train, holdout);
    return rho;
}

// The stored form: the kept joints' weight blocks per vertex, in vertex
// order, and the sizes the report gives.
void store_model(const TrainingSet& set, const FitSettings& settings, const FitShape& shape,
                 const std::vector<std::size_t>& active, PrunedModel& pruned, const Eigen::MatrixXf& W,
                 PoseModel& model, FitReport& report) {
    const std::size_t V = shape.V;
    const int d = shape.d;
    const KeptBlocks& kept = pruned.kept;
    model.bias = std::move(pruned.bias);
    model.order = shape.order;
    model.lobes = shape.lobes;
    model.rays = set.settings.rays;
    model.below_horizon = set.settings.below_horizon;
    model.features = settings.features;
    model.vertex_count = V;
    model.topology_hash = set.topology_hash;
    model.armature_bones = set.bone_names;
    for (auto b : active) model.joints.push_back(set.bone_names[b]);
    model.joint_offsets.assign(V + 1, 0);
    for (std::size_t v = 0; v < V; ++v) {
        model.joint_offsets[v + 1] = model.joint_offsets[v] + std::uint32_t(kept[v].size());
        if (kept[v].empty()) ++report.constant_vertices;
    }
    model.joint_index.reserve(model.joint_offsets[V]);
    std::vector<float> weights;
    for (std::size_t v = 0; v < V; ++v)
        for (const KeptBlock& b : kept[v]) {
            model.joint_index.push_back(b.joint);
            model.block_directions.push_back(b.directions);
            for (Eigen::Index a = shape.first(b.joint); a < shape.first(b.joint) + b.directions; ++a)
                for (int i = 0; i < d; ++i) weights.push_back(W(a, v * d + i));
        }
    set_weights(model, weights);  // W's kept blocks are already rounded (prune): this packs them exactly
    report.stored_joint_blocks = model.joint_index.size();
    report.stored_directions = model.weights.size() / std::size_t(d);
    report.model_bytes = 4 * model.joint_offsets.size() + 2 * model.joint_index.size() + 4 * model.bias.size() +
                         8 * model.weight_offsets.size() + 2 * model.weights.size() + 4 * model.weight_scales.size() +
                         model.block_directions.size() +
                         4 * model.feature_offsets.size() + 4 * model.feature_basis.size();
    report.dense_bytes = 4 * std::size_t(d) * (active.size() * shape.fpj + 1) * V;
}

// The report's numbers, stored with the model as (name, value).
std::vector<std::pair<std::string, double>> model_summary(const FitReport& report, std::size_t frames,
                                                          std::size_t active_joints) {
    return {
        {"frames", double(frames)},
        {"holdout_frames", double(report.holdout_frames)},
        {"active_joints", double(active_joints)},
        {"zh_fit_sh_rms", report.zh_fit.sh_rms},
        {"zh_fit_ao_mean_abs", report.zh_fit.ao_mean_abs},
        {"training_sh_rms", report.model_training.sh_rms},
        {"training_ao_mean_abs", report.model_training.ao_mean_abs},
        {"holdout_sh_rms", report.model_holdout.sh_rms},
        {"holdout_ao_mean_abs", report.model_holdout.ao_mean_abs},
        {"holdout_ao_max_abs", report.model_holdout.ao_max_abs},
        {"holdout_unpruned_sh_rms", report.model_holdout_unpruned.sh_rms},
        {"holdout_unpruned_ao_mean_abs", report.model_holdout_unpruned.ao_mean_abs},
        {"ridge_relative", report.ridge_relative},
        {"constant_vertices", double(report.constant_vertices)},
        {"stored_joint_blocks", double(report.stored_joint_blocks)},
        {"model_bytes", double(report.model_bytes)},
        {"dense_bytes", double(report.dense_bytes)},
        {"seconds_zh_fit", report.seconds_zh_fit},
        {"seconds_linear", report.seconds_linear},
    };
}

}  // namespace

PoseModel fit_pose_model(const TrainingSet& set, const std::vector<BoneInfluence>& influence,
                         const FitSettings& settings, const Progress& progress, FitReport* report_out) {
    check_fit_settings(settings);
    check_training_set(set);
    if (set.settings.weighting != Weighting::Plain && set.settings.weighting != Weighting::Cosine)
        throw ArgumentError("unknown weighting");
    if (set.frames.empty()) throw ArgumentError("the training set has no frames");
    if (set.vertex_count == 0) throw ArgumentError("the training set has no vertices");
    FitShape shape{};
    shape.order = set.settings.order;
    shape.lobes = settings.lobes;
    shape.n_sh = shape.order * shape.order;
    shape.d = shape.lobes * params_per_lobe(shape.order);
    shape.fpj = features_per_joint(settings.features);
    shape.V = set.vertex_count;
    shape.F = set.frames.size();
    FitReport report;

    // ZH lobes per vertex and frame (fig. 2b): rows of B.
    const auto t_zh = Clock::now();
    ErrorSums zh_errors;
    const Eigen::MatrixXf B = fit_frame_lobes(set, settings, shape, progress, zh_errors);
    report.zh_fit = zh_errors.result();
    report.seconds_zh_fit = seconds_since(t_zh);

    // Active joints and the pose matrix A (without its bias column).
    const auto t_linear = Clock::now();
    report.joints = choose_active_joints(set, influence, settings.joint_tolerance_degrees);
    std::vector<std::size_t> active;
    for (std::size_t b = 0; b < report.joints.size(); ++b)
        if (report.joints[b].active) active.push_back(b);
    if (active.size() > 65535) throw ArgumentError("too many active joints");
    std::vector<std::size_t> train, holdout;
    split_frames(shape.F, settings.holdout_stride, train, holdout);
    // Each joint's feature directions, decided on the training frames like
    // everything the held-out error measures.
    PoseModel model;
    const Eigen::MatrixXd raw = raw_pose_matrix(set, active, settings.features);
    FeatureDirections directions = principal_feature_directions(raw, train, shape.fpj, settings.feature_tolerance);
    shape.feature_start.assign(directions.offsets.begin(), directions.offsets.end());
    shape.k = shape.feature_start.back();
    for (std::size_t j = 0; j < active.size(); ++j)
        report.joints[active[j]].feature_directions = int(directions.offsets[j + 1] - directions.offsets[j]);
    const Eigen::MatrixXd A = project_pose_matrix(raw, shape.fpj, directions);
    model.feature_offsets = std::move(directions.offsets);
    model.feature_basis = std::move(directions.basis);
    const LinearFit fit(set, settings, shape, A, B);

    // λ from the held-out frames, then the refit on every frame.
    report.training_frames = shape.F;
    report.holdout_frames = holdout.size();
    const double rho = choose_ridge(fit, A, B, shape, train, holdout, settings.threads, progress, report);
    report.ridge_relative = rho;
    std::vector<std::size_t> all(shape.F);
    std::iota(all.begin(), all.end(), std::size_t(0));
    const RidgeSolver sol = fit.solver(all);
    Eigen::MatrixXf W;
    if (shape.k) W = sol.weights(rho, settings.threads);

    // Pruned, as stored, by the same rule on every frame with the weights
    // it stores. Reusing the choices made on the training frames with the
    // training frames' weights (as before) dropped directions that the
    // refitted weights lean on: on the procedural character at 64 rays an
    // unseen AO error of 2.49 at one vertex against 0.57 unpruned
    // (docs/visibility-benchmark.md, "The tail of pruning").
    PrunedModel pruned = fit.prune(all, sol, W, progress, 0.9, 0.95);
    report.model_training = fit.pruned_errors(pruned, W, all);
    store_model(set, settings, shape, active, pruned, W, model, report);
    report.seconds_linear = seconds_since(t_linear);
    if (report.holdout_frames == 0) report.model_holdout = report.model_holdout_unpruned = Errors{};
    model.summary = model_summary(report, shape.F, active.size());
    if (report_out) *report_out = std::move(report);
    return model;
}

Errors evaluate_pose_model(const PoseModel& model, const TrainingSet& set, int threads) {
    check_pose_model(model);
    check_training_set(set);
    if (set.vertex_count != model.vertex_count) throw ArgumentError("the frames were baked from another mesh");
    if (set.settings.order != model.order) throw ArgumentError("the frames were baked at another SH order");
    std::vector<std::size_t> bone_of(model.joints.size());
    for (std::size_t j = 0; j < model.joints.size(); ++j) {
        auto it = std::find(set.bone_names.begin(), set.bone_names.end(), model.joints[j]);
        if (it == set.bone_names.end()) throw ArgumentError("the frames lack the model's joint '" + model.joints[j] + "'");
        bone_of[j] = std::size_t(it - set.bone_names.begin());
    }
    const int d = model.params_per_vertex(), n_sh = model.order * model.order;
    ErrorSums total;
    std::vector<float> rotations(9 * model.joints.size()), params(model.vertex_count * d);
    for (const auto& frame : set.frames) {
        for (std::size_t j = 0; j < bone_of.size(); ++j)
            std::copy_n(frame.bone_rotations.data() + 9 * bone_of[j], 9, rotations.data() + 9 * j);
        synthesize_params(model, rotations.data(), params.data(), threads);
        std::vector<double> p(d), sh(n_sh);
        for (std::size_t v = 0; v < model.vertex_count; ++v) {
            for (int i = 0; i < d; ++i) p[i] = params[v * d + i];
            lobes_to_sh(model.order, model.lobes, p.data(), sh.data());
            total.add(model.order, sh.data(), frame.visibility.data() + v * n_sh);
        }
    }
    return total.result();
}

}  // namespace penumbra::visibility
