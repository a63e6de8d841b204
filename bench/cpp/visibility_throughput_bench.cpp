// Raw Embree occlusion throughput on a mesh given as three raw files, for
// bench/visibility_benchmark.py (which writes them from Blender's meshes):
//   penumbra_visibility_throughput_bench POSITIONS.f32 NORMALS.f32 TRIANGLES.u32 RAYS THREADS single|packet
// Prints one JSON object: rays, seconds, rays_per_second, occluded_fraction, packet_width.
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <vector>

#include "visibility_throughput.hpp"

namespace {

template <class T>
std::vector<T> read_raw(const char* path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error(std::string("cannot read ") + path);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::vector<T> values(bytes.size() / sizeof(T));
    std::copy(bytes.begin(), bytes.begin() + std::ptrdiff_t(values.size() * sizeof(T)),
              reinterpret_cast<char*>(values.data()));
    return values;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 7) {
        std::cerr << "usage: " << argv[0] << " POSITIONS.f32 NORMALS.f32 TRIANGLES.u32 RAYS THREADS single|packet\n";
        return 2;
    }
    try {
        const auto r = penumbra::visibility::measure_occlusion_throughput(
            read_raw<float>(argv[1]), read_raw<float>(argv[2]), read_raw<std::uint32_t>(argv[3]),
            std::atoi(argv[4]), std::atoi(argv[5]), argv[6]);
        std::printf("{\"rays\": %zu, \"seconds\": %.9g, \"rays_per_second\": %.9g, \"occluded_fraction\": %.9g, "
                    "\"packet_width\": %d}\n",
                    r.rays, r.seconds, r.rays_per_second, r.occluded_fraction, r.packet_width);
    } catch (const std::exception& e) {
        std::cerr << e.what() << "\n";
        return 1;
    }
    return 0;
}
