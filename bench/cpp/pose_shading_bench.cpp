// Pose shading speed (sh/pose_shading.hpp): ns per vertex for one pose, beside
// a memory-streaming baseline over the same bytes measured in the same run
// (a loop that reads every input byte the shader reads and writes the same
// output bytes), so "× stream" says how far above the bandwidth limit the
// shader is. Also the straightforward per-vertex reference path (full SH
// rotation of the RGB lighting per vertex), float vs double buffers, and the
// order, and each SIMD target the CPU supports against the scalar one. Prints a Markdown table; bench/sh_shading_benchmark.py writes it to
// docs/sh-shading-benchmark.md. Not a test: `make bench` runs it.
//
//   penumbra_pose_shading_bench [--quick]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <numbers>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "sh/brdf_operator.hpp"
#include "sh/pose_shading.hpp"
#include "sh/rotation.hpp"
#include "sh/zonal.hpp"

namespace {

using namespace penumbra::sh;
using Clock = std::chrono::steady_clock;

template <typename Real>
struct PoseData {
    int order, lobes;
    std::size_t n;
    std::vector<Real> axes, bands, normals, tangents, positions, rgb, visibility;

    PoseData(int order_, int lobes_, std::size_t n_, std::uint64_t seed) : order(order_), lobes(lobes_), n(n_) {
        std::mt19937_64 rng(seed);
        std::normal_distribution<double> normal;
        std::uniform_real_distribution<double> uniform(-1.0, 1.0);
        const auto fill = [&](std::vector<Real>& v, std::size_t count, auto draw) {
            v.resize(count);
            for (Real& e : v) e = Real(draw());
        };
        fill(axes, n * lobes * 3, [&] { return normal(rng); });
        fill(bands, n * lobes * order, [&] { return uniform(rng); });
        fill(normals, n * 3, [&] { return normal(rng); });
        fill(tangents, n * 3, [&] { return normal(rng); });
        fill(positions, n * 3, [&] { return uniform(rng); });
        rgb.assign(n * 3, Real(0));
        visibility.assign(n, Real(0));
    }

    PoseBuffers<Real> buffers(bool with_visibility = false) {
        return {n, lobes, axes.data(), bands.data(), normals.data(), tangents.data(), positions.data(), rgb.data(),
                with_visibility ? visibility.data() : nullptr};
    }
};

// Median wall times of `repeats` runs of a and of b (after one warm-up
// each), alternating a and b so that both see the same machine load.
std::pair<double, double> median_seconds(int repeats, const std::function<void()>& a, const std::function<void()>& b) {
    a();
    b();
    std::vector<double> times_a, times_b;
    for (int r = 0; r < repeats; ++r) {
        for (auto [work, times] : {std::pair{&a, &times_a}, std::pair{&b, &times_b}}) {
            const auto start = Clock::now();
            (*work)();
            times->push_back(std::chrono::duration<double>(Clock::now() - start).count());
        }
    }
    for (std::vector<double>* times : {&times_a, &times_b})
        std::nth_element(times->begin(), times->begin() + times->size() / 2, times->end());
    return {times_a[times_a.size() / 2], times_b[times_b.size() / 2]};
}

// The baseline: reads every input value of a vertex (as the shader does) and
// writes 3 outputs, split over `threads` threads like the shader.
template <typename Real>
void stream(PoseData<Real>& d, bool with_positions, int threads) {
    const auto range = [&](std::size_t begin, std::size_t end) {
        const std::size_t per_lobe_values = std::size_t(d.lobes) * (3 + d.order);
        for (std::size_t i = begin; i < end; ++i) {
            Real sum = 0, sum2 = 0, sum3 = 0;
            const Real* a = d.axes.data() + i * d.lobes * 3;
            const Real* b = d.bands.data() + i * d.lobes * d.order;
            for (std::size_t k = 0; k < std::size_t(d.lobes) * 3; ++k) sum += a[k];
            for (std::size_t k = 0; k < per_lobe_values - std::size_t(d.lobes) * 3; ++k) sum2 += b[k];
            for (int k = 0; k < 3; ++k) {
                sum3 += d.normals[3 * i + k] + d.tangents[3 * i + k];
                if (with_positions) sum3 += d.positions[3 * i + k];
            }
            d.rgb[3 * i] = sum;
            d.rgb[3 * i + 1] = sum2;
            d.rgb[3 * i + 2] = sum3;
        }
    };
    std::vector<std::thread> workers;
    const std::size_t per = (d.n + threads - 1) / threads;
    for (int t = 1; t < threads; ++t)
        workers.emplace_back(range, std::min(d.n, t * per), std::min(d.n, (t + 1) * per));
    range(0, std::min(d.n, per));
    for (std::thread& w : workers) w.join();
}

// The straightforward path the "reference" rows time: per vertex, the frame
// G (z = n, or Phong's reflection r clamped to the horizon), the lobes
// expanded in G (Eq. 1), T applied, and the RGB lighting rotated into G by a
// full Ivanic–Ruedenberg ShRotation(Gᵀ), the per-vertex rotation the fast
// path avoids. A timing copy, diffuse and Phong without the visibility
// output, of shade_pose_reference in tests/cpp/sh/pose_shading_reference.hpp,
// the copy the tests check the fast path against.
void shade_straightforward(int order, const Eigen::MatrixXd& lighting, const ShadingParameters& parameters,
                           const PoseBuffers<double>& b) {
    const int count = coefficient_count(order);
    const ZonalOperator op = parameters.model == ShadingModel::phong
                                 ? phong_zonal_operator(order, parameters.phong_exponent)
                                 : diffuse_zonal_operator(order);
    std::vector<double> v(count), u(count), lit(count), light(count);
    for (std::size_t i = 0; i < b.vertex_count; ++i) {
        const Eigen::Vector3d n =
            Eigen::Vector3d(b.normals[3 * i], b.normals[3 * i + 1], b.normals[3 * i + 2]).normalized();
        Eigen::Vector3d t(b.tangents[3 * i], b.tangents[3 * i + 1], b.tangents[3 * i + 2]);
        t = (t - t.dot(n) * n).normalized();
        Eigen::Matrix3d frame;
        frame << t, n.cross(t), n;
        Eigen::Vector3d z = n;
        if (parameters.model == ShadingModel::phong) {
            const Eigen::Vector3d p(b.positions[3 * i], b.positions[3 * i + 1], b.positions[3 * i + 2]);
            const Eigen::Vector3d w = (parameters.camera - p).normalized();
            const double cosine = n.dot(w);
            const Eigen::Vector3d h = w - cosine * n;
            if (cosine >= 0.0) z = (2.0 * cosine * n - w).normalized();
            else if (h.norm() > 1e-12) z = -h.normalized();
        }
        // G: any rotation with G e_z = z.
        Eigen::Vector3d gx = (std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY());
        gx = (gx - gx.dot(z) * z).normalized();
        Eigen::Matrix3d g;
        g << gx, z.cross(gx), z;

        std::fill(v.begin(), v.end(), 0.0);
        for (int c = 0; c < b.lobes_per_vertex; ++c) {
            const std::size_t at = i * b.lobes_per_vertex + c;
            const Eigen::Vector3d axis(b.lobe_axes[3 * at], b.lobe_axes[3 * at + 1], b.lobe_axes[3 * at + 2]);
            zh_to_sh_accumulate(order, g.transpose() * frame * axis, b.lobe_bands + order * at, v.data());
        }
        op.apply(v.data(), u.data());
        // Lighting into G: f_G(ω') = f(G ω'), i.e. f turned by Gᵀ.
        const ShRotation into_frame(order, g.transpose());
        for (int channel = 0; channel < 3; ++channel) {
            for (int k = 0; k < count; ++k) light[k] = lighting(k, channel);
            into_frame.apply(light.data(), lit.data());
            double shade = 0.0;
            for (int k = 0; k < count; ++k) shade += lit[k] * u[k];
            b.rgb[3 * i + channel] = shade;
        }
    }
}

struct Row {
    std::string what;
    std::size_t n;
    int lobes, order, threads;
    std::string model, real;
    double ns_per_vertex, stream_ns_per_vertex;
};

}  // namespace

int main(int argc, char** argv) {
    const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
    const int all = int(std::max(1u, std::thread::hardware_concurrency()));
    const int repeats = quick ? 5 : 21;
    const double alpha = 32.0;

    std::vector<Row> rows;
    const auto run_case = [&](auto real_tag, const char* real_name, std::size_t n, int lobes, int order,
                              ShadingModel model, int threads) {
        using Real = decltype(real_tag);
        PoseData<Real> d(order, lobes, n, 1234 + n + lobes);
        const PoseShader shader(order);
        std::mt19937_64 rng(99);
        std::uniform_real_distribution<double> uniform(-1.0, 1.0);
        Eigen::MatrixXd lighting(coefficient_count(order), 3);
        for (Eigen::Index i = 0; i < lighting.size(); ++i) lighting.data()[i] = uniform(rng);
        ShadingParameters p;
        p.model = model;
        p.phong_exponent = alpha;
        p.camera = Eigen::Vector3d(0.5, -4.0, 1.5);
        p.threads = threads;
        const PoseBuffers<Real> b = d.buffers();
        const bool phong = model == ShadingModel::phong;
        const auto [shade, streaming] = median_seconds(repeats, [&] { shader.shade(lighting, p, b); },
                                                       [&] { stream(d, phong, threads); });
        rows.push_back({"batched " + simd_target(), n, lobes, order, threads, phong ? "phong" : model == ShadingModel::diffuse ? "diffuse" : "translucent",
                        real_name, shade / n * 1e9, streaming / n * 1e9});
    };

    // The grid: 10k/100k × 1/2 lobes × diffuse/phong × 1/all threads, order 4, float32.
    for (std::size_t n : {std::size_t(10000), std::size_t(100000)})
        for (int lobes : {1, 2})
            for (ShadingModel model : {ShadingModel::diffuse, ShadingModel::phong})
                for (int threads : {1, all}) run_case(float{}, "float32", n, lobes, 4, model, threads);
    // float32 vs float64 buffers, translucency, and the order.
    for (int threads : {1, all}) {
        run_case(double{}, "float64", 100000, 2, 4, ShadingModel::diffuse, threads);
        run_case(double{}, "float64", 100000, 2, 4, ShadingModel::phong, threads);
        run_case(float{}, "float32", 100000, 2, 4, ShadingModel::translucent, threads);
    }
    for (int order : {2, 3, 5, 6, 8, 10})
        run_case(float{}, "float32", 100000, 2, order, ShadingModel::diffuse, 1);

    // Every SIMD target compiled in (run-time dispatch; the CPU's best is the
    // default above) on the run time's case, one thread: the gain of each
    // over the one-lane scalar reference, in the same run.
    for (const std::string& target : simd_targets()) {
        force_simd_target(target);
        run_case(float{}, "float32", 100000, 2, 4, ShadingModel::phong, 1);
    }
    force_simd_target("");

    // The straightforward path (shade_straightforward), single thread, double.
    {
        const std::size_t n = quick ? 2000 : 10000;
        for (ShadingModel model : {ShadingModel::diffuse, ShadingModel::phong}) {
            PoseData<double> d(4, 2, n, 77);
            std::mt19937_64 rng(5);
            std::uniform_real_distribution<double> uniform(-1.0, 1.0);
            Eigen::MatrixXd lighting(16, 3);
            for (Eigen::Index i = 0; i < lighting.size(); ++i) lighting.data()[i] = uniform(rng);
            ShadingParameters p;
            p.model = model;
            p.phong_exponent = alpha;
            p.camera = Eigen::Vector3d(0.5, -4.0, 1.5);
            const PoseBuffers<double> b = d.buffers();
            const auto [reference, streaming] =
                median_seconds(quick ? 1 : 3, [&] { shade_straightforward(4, lighting, p, b); },
                               [&] { stream(d, model == ShadingModel::phong, 1); });
            rows.push_back({"reference", n, 2, 4, 1, model == ShadingModel::phong ? "phong" : "diffuse", "float64",
                            reference / n * 1e9, streaming / n * 1e9});
        }
    }

    std::printf("| path | vertices | lobes | order | model | buffers | threads | ns/vertex | stream ns/vertex | × stream | ms/pose |\n");
    std::printf("|---|---:|---:|---:|---|---|---:|---:|---:|---:|---:|\n");
    for (const Row& r : rows)
        std::printf("| %s | %zu | %d | %d | %s | %s | %d | %.1f | %.2f | %.0f | %.3f |\n", r.what.c_str(), r.n, r.lobes,
                    r.order, r.model.c_str(), r.real.c_str(), r.threads, r.ns_per_vertex, r.stream_ns_per_vertex,
                    r.ns_per_vertex / r.stream_ns_per_vertex, r.ns_per_vertex * r.n * 1e-6);
    std::printf("\nthreads: %d hardware threads; Phong exponent %.0f; median of %d runs after a warm-up.\n", all, alpha,
                repeats);
    return 0;
}
