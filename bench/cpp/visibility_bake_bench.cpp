// The visibility bake's casting on frames written to a folder, one way of
// casting against another in the same run (bench/visibility_bake_bench.py
// writes the humanoid's frames and runs it):
//   penumbra_visibility_bake_bench FOLDER FRAMES RAYS REPEATS MODE...
// FOLDER holds neighbours.u32 and per frame k (000, 001, ...) pKKK.f32
// (positions), nKKK.f32 (normals), tKKK.u32 (triangles).
// MODE: single|coherent, then ':'-separated options: fast|robust (Embree's
// traversal, visibility/occlusion_scene.hpp; default fast), medium|high|low|
// refit (the scene build; single only), 4|8|16 (coherent: packet width,
// default the CPU's) and same (coherent: every lane takes its group
// leader's direction, the coherence a perfect pairing would reach; wrong
// visibility, for the speed bound only).
//   single: the library's bake (FrameBaker), each vertex's rays one by one.
//   coherent: neighbouring vertices (Morton order) in groups of the packet
//     width; one packet holds one ray of each vertex of a group, the rays
//     paired so that their world directions nearly agree (each vertex's
//     latitude bands of directions turned by its tangent's angle to the
//     leader's); rtcOccluded16/8/4.
// The modes run in turn, REPEATS times each (A/B alternated), each baking
// the FRAMES frames as the bake does. Prints one JSON line per run: mode,
// wall and CPU seconds (CPU time is steadier on a shared machine), seconds
// per phase, rays per second while casting, and the (vertex, frame) pairs
// whose SH visibility differs from the first run's (0: bit-identical), or
// from the file named by $PENUMBRA_BAKE_REFERENCE (written by the first run
// when it does not exist: a baseline from another build).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <iostream>
#include <iterator>
#include <numbers>
#include <numeric>
#include <string>
#include <vector>

#include "common/parallel.hpp"
#include "visibility/visibility_bake.hpp"

namespace vis = penumbra::visibility;

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

template <class T>
std::vector<T> read_raw(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot read " + path);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::vector<T> values(bytes.size() / sizeof(T));
    std::copy(bytes.begin(), bytes.begin() + std::ptrdiff_t(values.size() * sizeof(T)),
              reinterpret_cast<char*>(values.data()));
    return values;
}

std::string frame_file(const std::string& folder, char kind, int k, const char* ext) {
    char name[32];
    std::snprintf(name, sizeof name, "/%c%03d.%s", kind, k, ext);
    return folder + name;
}

struct Mode {
    std::string name;
    bool coherent = false, same_direction = false;
    vis::Traversal traversal = vis::Traversal::Fast;
    vis::SceneBuild build = vis::SceneBuild::Medium;
    int width = 0;  // 0: the CPU's packet width
};

Mode parse_mode(const std::string& text) {
    Mode m{text};
    std::size_t start = 0;
    for (bool first = true;; first = false) {
        const std::size_t colon = text.find(':', start);
        const std::string token = text.substr(start, colon - start);
        if (first && (token == "single" || token == "coherent")) m.coherent = token == "coherent";
        else if (first) throw std::runtime_error("a mode starts with single or coherent: " + text);
        else if (token == "fast") m.traversal = vis::Traversal::Fast;
        else if (token == "robust") m.traversal = vis::Traversal::Robust;
        else if (token == "medium") m.build = vis::SceneBuild::Medium;
        else if (token == "high") m.build = vis::SceneBuild::High;
        else if (token == "low") m.build = vis::SceneBuild::Low;
        else if (token == "refit") m.build = vis::SceneBuild::Refit;
        else if (token == "same") m.same_direction = true;
        else if (token == "4" || token == "8" || token == "16") m.width = std::stoi(token);
        else throw std::runtime_error("unknown mode option " + token);
        if (colon == std::string::npos) break;
        start = colon + 1;
    }
    return m;
}

// Z-order (Morton) curve over the positions' bounding box, 10 bits an axis.
std::vector<std::uint32_t> morton_order(const std::vector<float>& positions) {
    const std::size_t n = positions.size() / 3;
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(INFINITY), hi = Eigen::Vector3f::Constant(-INFINITY);
    for (std::size_t v = 0; v < n; ++v) {
        const Eigen::Vector3f p(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]);
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    const float scale = 1023.0f / std::max((hi - lo).maxCoeff(), 1e-30f);
    const auto spread = [](std::uint32_t x) {
        std::uint32_t r = 0;
        for (int b = 0; b < 10; ++b) r |= ((x >> b) & 1u) << (3 * b);
        return r;
    };
    std::vector<std::uint32_t> code(n), order(n);
    for (std::size_t v = 0; v < n; ++v)
        for (int a = 0; a < 3; ++a)
            code[v] |= spread(std::uint32_t(std::clamp((positions[3 * v + a] - lo[a]) * scale, 0.0f, 1023.0f))) << a;
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return code[a] < code[b]; });
    return order;
}

// The upper hemisphere's directions [0, upper) in latitude bands of about
// √upper consecutive directions (Fibonacci order is by decreasing z), each
// listed by increasing azimuth.
std::vector<std::vector<std::uint32_t>> azimuth_bands(const vis::RaySet& rays) {
    const int count = rays.upper, n_bands = std::max(1, int(std::lround(std::sqrt(double(count)))));
    std::vector<std::vector<std::uint32_t>> bands(n_bands);
    for (int k = 0; k < n_bands; ++k) {
        for (int i = count * k / n_bands; i < count * (k + 1) / n_bands; ++i) bands[k].push_back(std::uint32_t(i));
        std::sort(bands[k].begin(), bands[k].end(), [&](std::uint32_t a, std::uint32_t b) {
            const auto phi = [&](std::uint32_t i) {
                const float p = std::atan2(rays.directions[i].y(), rays.directions[i].x());
                return p < 0.0f ? p + float(2.0 * std::numbers::pi) : p;
            };
            return phi(a) < phi(b);
        });
    }
    return bands;
}

// The coherent bake of one frame (below-horizon rays counted occluded, as
// the bake's default): writes V × order² like FrameBaker::bake.
struct CoherentBaker {
    CoherentBaker(const vis::BakeSettings& s, const Mode& m)
        : settings(s), mode(m), rays(vis::make_ray_set(s)), bands(azimuth_bands(rays)) {}
    vis::BakeSettings settings;
    Mode mode;
    vis::RaySet rays;
    std::vector<std::vector<std::uint32_t>> bands;
    std::unique_ptr<vis::OcclusionScene> scene;

    void bake(const vis::FrameGeometry& g, const std::vector<std::uint32_t>& neighbours, float* out,
              vis::FrameBakeStats& stats);
};

void CoherentBaker::bake(const vis::FrameGeometry& g, const std::vector<std::uint32_t>& neighbours, float* out,
                         vis::FrameBakeStats& stats) {
    const auto t0 = Clock::now();
    const std::size_t V = g.mesh.vertex_count(), n_rays = rays.directions.size(), upper = std::size_t(rays.upper);
    const int n_sh = settings.order * settings.order;
    std::vector<float> frames(9 * V);
    vis::vertex_frames(g.mesh.positions, g.normals, g.mesh.triangles, neighbours, frames.data());
    const std::vector<std::uint32_t> order = morton_order(g.mesh.positions);
    const float offset = float(settings.offset_scale * vis::mesh_diagnostics(g.mesh.positions, g.normals, {}).bounding_diagonal);
    const auto t1 = Clock::now();
    if (!scene || !scene->update_positions({&g.mesh})) scene = std::make_unique<vis::OcclusionScene>(
        std::vector<const vis::TriangleMesh*>{&g.mesh}, vis::SceneBuild::Medium, mode.traversal);
    const auto t2 = Clock::now();
    const int width = mode.width ? mode.width : scene->packet_width();
    penumbra::parallel_for((V + width - 1) / width, {0, std::size_t(std::max(1, 64 / width))}, [&](std::size_t begin,
                                                                                                  std::size_t end) {
        std::vector<Eigen::Vector3f> world(width * n_rays), origin(width), lane(width);
        std::vector<std::uint32_t> slot(width * upper);
        std::vector<std::uint8_t> occluded(width * n_rays, 1), hit(width);
        for (std::size_t group = begin; group < end; ++group) {
            const std::uint32_t* vertex = order.data() + group * width;
            const int lanes = int(std::min<std::size_t>(width, V - group * width));
            const Eigen::Map<const Eigen::Vector3f> t0(frames.data() + 9 * vertex[0]);
            for (int j = 0; j < lanes; ++j) {
                const float* f = frames.data() + 9 * vertex[j];
                const Eigen::Vector3f t(f[0], f[1], f[2]), b(f[3], f[4], f[5]), n(f[6], f[7], f[8]);
                for (std::size_t i = 0; i < upper; ++i) {
                    const Eigen::Vector3f& d = rays.directions[i];
                    world[j * n_rays + i] = d.x() * t + d.y() * b + d.z() * n;
                }
                const Eigen::Vector3f p(g.mesh.positions[3 * vertex[j]], g.mesh.positions[3 * vertex[j] + 1],
                                        g.mesh.positions[3 * vertex[j] + 2]);
                origin[j] = p + offset * n;
                // Turn of this tangent from the leader's, as a fraction of a circle.
                double turn = std::atan2(double(t0.dot(b)), double(t0.dot(t))) / (2.0 * std::numbers::pi);
                if (turn < 0.0) turn += 1.0;
                std::size_t s = 0;
                for (const auto& band : bands) {
                    const std::size_t m = band.size(), shift = std::size_t(std::lround(turn * double(m))) % m;
                    for (std::size_t k = 0; k < m; ++k) slot[j * upper + s++] = band[(k + shift) % m];
                }
            }
            for (std::size_t s = 0; s < upper; ++s) {
                for (int j = 0; j < lanes; ++j)
                    lane[j] = mode.same_direction ? world[slot[s]] : world[j * n_rays + slot[j * upper + s]];
                scene->occluded_packet(origin.data(), lane.data(), lanes, 0.0f, INFINITY, hit.data(), width);
                for (int j = 0; j < lanes; ++j) occluded[j * n_rays + slot[j * upper + s]] = hit[j];
            }
            for (int j = 0; j < lanes; ++j) {
                float* sh = out + std::size_t(vertex[j]) * n_sh;
                std::fill(sh, sh + n_sh, 0.0f);
                for (std::size_t i = 0; i < upper; ++i) {
                    if (occluded[j * n_rays + i]) continue;
                    const float* row = rays.projection.data() + i * n_sh;
                    for (int k = 0; k < n_sh; ++k) sh[k] += row[k];
                }
            }
        }
    });
    stats.seconds_setup = std::chrono::duration<double>(t1 - t0).count();
    stats.seconds_build = std::chrono::duration<double>(t2 - t1).count();
    stats.seconds_cast = since(t2);
    stats.rays_cast = V * upper;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 6) {
        std::cerr << "usage: " << argv[0] << " FOLDER FRAMES RAYS REPEATS MODE...\n";
        return 2;
    }
    try {
        const std::string folder = argv[1];
        const int n_frames = std::atoi(argv[2]), repeats = std::atoi(argv[4]);
        vis::BakeSettings settings;
        settings.rays = std::atoi(argv[3]);
        const auto neighbours = read_raw<std::uint32_t>(folder + "/neighbours.u32");
        std::vector<vis::FrameGeometry> frames(n_frames);
        for (int k = 0; k < n_frames; ++k) {
            frames[k].mesh.positions = read_raw<float>(frame_file(folder, 'p', k, "f32"));
            frames[k].normals = read_raw<float>(frame_file(folder, 'n', k, "f32"));
            frames[k].mesh.triangles = read_raw<std::uint32_t>(frame_file(folder, 't', k, "u32"));
        }
        const std::size_t V = neighbours.size(), n_sh = std::size_t(settings.order) * settings.order;
        std::vector<Mode> modes;
        for (int a = 5; a < argc; ++a) modes.push_back(parse_mode(argv[a]));
        std::vector<float> first, out(n_frames * V * n_sh);
        for (int r = 0; r < repeats; ++r)
            for (const Mode& mode : modes) {
                vis::FrameBaker baker(settings, mode.build, mode.traversal);
                CoherentBaker coherent(settings, mode);
                vis::FrameBakeStats total, stats;
                const auto start = Clock::now();
                const std::clock_t cpu_start = std::clock();
                for (int k = 0; k < n_frames; ++k) {
                    float* sh = out.data() + k * V * n_sh;
                    if (mode.coherent) coherent.bake(frames[k], neighbours, sh, stats);
                    else baker.bake(frames[k], neighbours, sh, {}, &stats);
                    total.seconds_setup += stats.seconds_setup;
                    total.seconds_build += stats.seconds_build;
                    total.seconds_cast += stats.seconds_cast;
                    total.rays_cast += stats.rays_cast;
                }
                const double seconds = since(start), cpu = double(std::clock() - cpu_start) / CLOCKS_PER_SEC;
                if (first.empty()) {
                    first = out;
                    if (const char* path = std::getenv("PENUMBRA_BAKE_REFERENCE")) {
                        std::ifstream in(path, std::ios::binary);
                        if (in) in.read(reinterpret_cast<char*>(first.data()), std::streamsize(first.size() * sizeof(float)));
                        else std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(out.data()),
                                                                         std::streamsize(out.size() * sizeof(float)));
                    }
                }
                std::size_t differing = 0;
                for (std::size_t i = 0; i < out.size(); i += n_sh)
                    differing += !std::equal(out.begin() + i, out.begin() + i + n_sh, first.begin() + i);
                std::printf("{\"mode\": \"%s\", \"repeat\": %d, \"seconds\": %.4f, \"cpu_seconds\": %.4f, "
                            "\"setup\": %.4f, \"build\": %.4f, \"cast\": %.4f, \"mrays_per_second\": %.3f, "
                            "\"vertex_frames_differing\": %zu}\n",
                            mode.name.c_str(), r, seconds, cpu, total.seconds_setup, total.seconds_build,
                            total.seconds_cast, double(total.rays_cast) / total.seconds_cast / 1e6, differing);
                std::fflush(stdout);
            }
    } catch (const std::exception& e) {
        std::cerr << e.what() << "\n";
        return 1;
    }
    return 0;
}
