// Writes the seed corpora of the C++ harnesses that have to be made by code
// (docs/reliability.md): small valid visibility files written by the core's
// own writers, small images of every kind the readers meet (through
// OpenImageIO, as other programs write them), and the structured inputs of
// the colour-map harnesses. Run by tests/fuzz/make_seeds.sh (`make
// fuzz-seeds`), which adds the video seeds with ffmpeg. Usage:
//   fuzz_make_seeds <tests/fuzz folder>
// Overwrites the seeds it makes; leaves everything else in the corpora.
#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "image/image_io.hpp"
#include "visibility/model_file.hpp"
#include "visibility/pose_model.hpp"

using namespace penumbra;
using namespace penumbra::visibility;
namespace fs = std::filesystem;

namespace {

fs::path root;

fs::path corpus(const std::string& harness) {
    const fs::path dir = root / harness / "corpus";
    fs::create_directories(dir);
    return dir;
}

void write_bytes(const fs::path& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    if (!out) throw std::runtime_error("cannot write " + path.string());
    std::printf("%s (%zu bytes)\n", path.string().c_str(), bytes.size());
}

std::string read_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

// --- visibility files ------------------------------------------------------

PoseModel small_model(PoseFeatures features) {
    PoseModel m;
    m.order = 2;
    m.lobes = 1;
    m.rays = 16;
    m.features = features;
    m.vertex_count = 3;
    m.topology_hash = 0x1234;
    m.armature_bones = {"root", "arm", "hand"};
    m.joints = {"arm", "hand"};
    m.joint_offsets = {0, 1, 1, 3};
    m.joint_index = {0, 0, 1};
    const std::size_t d = std::size_t(m.params_per_vertex()), f = std::size_t(features_per_joint(features));
    for (std::size_t i = 0; i < m.vertex_count * d; ++i) m.bias.push_back(0.1f * float(i % 7));
    use_raw_joint_features(m);
    // As a fit stores them: the hand moves along 2 directions (its first two
    // raw entries), and the blocks keep 2, all and 1 of their joint's.
    m.feature_offsets[2] = m.feature_offsets[1] + 2;
    m.feature_basis.resize(m.feature_offsets[2] * f);
    m.block_directions = {2, std::uint8_t(f), 1};
    std::vector<float> weights;
    for (std::size_t i = 0; i < (3 + f) * d; ++i) weights.push_back(0.01f * float(i % 5) - 0.02f);
    set_weights(m, weights);
    m.summary = {{"frames", 3.0}, {"zh_fit_rms", 0.01}};
    return m;
}

TrainingSet small_training_set(int frames, std::uint64_t vertices) {
    TrainingSet s;
    s.settings.order = 2;
    s.settings.rays = 16;
    s.vertex_count = vertices;
    s.topology_hash = 0x1234;
    s.bone_names = {"root", "arm"};
    for (int f = 0; f < frames; ++f) {
        TrainingFrame frame;
        frame.frame = 1.0 + f;
        for (int b = 0; b < 2; ++b)
            for (int k = 0; k < 9; ++k) frame.bone_rotations.push_back(k % 4 == 0 ? 1.0f : 0.0f);
        for (std::uint64_t i = 0; i < vertices * 4; ++i) frame.visibility.push_back(0.25f * float((i + f) % 5));
        s.frames.push_back(frame);
    }
    return s;
}

void visibility_seeds() {
    const fs::path dir = corpus("visibility_file");
    write_pose_model((dir / "model_matrix.pzh").string(), small_model(PoseFeatures::RotationMatrix));
    write_pose_model((dir / "model_vector.pzh").string(), small_model(PoseFeatures::RotationVector));
    write_training_set((dir / "training_three_frames.pvis").string(), small_training_set(3, 2));
    write_training_set((dir / "training_no_frames.pvis").string(), small_training_set(0, 0));
    // The header alone, and a header whose reserved field is set (the harness
    // then keeps its size and checksum as they are: the header checks).
    std::string model = read_bytes(dir / "model_matrix.pzh");
    write_bytes(dir / "model_header_only.pzh", model.substr(0, 32));
    model[12] = 1;
    model[24] ^= 0x5a;
    write_bytes(dir / "model_bad_checksum.pzh", model);
    for (const char* name : {"model_matrix.pzh", "model_vector.pzh", "training_three_frames.pvis",
                             "training_no_frames.pvis"})
        std::printf("%s\n", (dir / name).string().c_str());
}

// --- images ----------------------------------------------------------------

std::vector<float> ramp_pixels(int w, int h, int c) {
    std::vector<float> p(std::size_t(w) * h * c);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int k = 0; k < c; ++k) p[(std::size_t(y) * w + x) * c + k] = 0.1f * float(x + 2 * y + k) + 0.05f;
    return p;
}

void oiio_write(const fs::path& path, OIIO::ImageSpec spec, int subimages = 1) {
    auto out = OIIO::ImageOutput::create(path.string());
    if (!out) throw std::runtime_error("no writer for " + path.string());
    std::vector<OIIO::ImageSpec> specs(subimages, spec);
    const auto pixels = ramp_pixels(spec.width, spec.height, spec.nchannels);
    if (!out->open(path.string(), subimages, specs.data())) throw std::runtime_error(out->geterror());
    for (int s = 0; s < subimages; ++s) {
        if (s > 0 && !out->open(path.string(), specs[s], OIIO::ImageOutput::AppendSubimage))
            throw std::runtime_error(out->geterror());
        if (!out->write_image(OIIO::TypeDesc::FLOAT, pixels.data())) throw std::runtime_error(out->geterror());
    }
    out->close();
    std::printf("%s (%ju bytes)\n", path.string().c_str(), std::uintmax_t(fs::file_size(path)));
}

void image_seeds() {
    const fs::path dir = corpus("image_file");
    using OIIO::TypeDesc;
    OIIO::ImageSpec rgb_half(8, 4, 3, TypeDesc::HALF);
    rgb_half.attribute("compression", "zip");
    oiio_write(dir / "rgb_half_zip.exr", rgb_half);
    OIIO::ImageSpec rgb_float(8, 4, 3, TypeDesc::FLOAT);
    rgb_float.attribute("compression", "none");
    oiio_write(dir / "rgb_float.exr", rgb_float);
    OIIO::ImageSpec tiled(8, 4, 3, TypeDesc::HALF);
    tiled.tile_width = tiled.tile_height = 4;
    tiled.attribute("compression", "piz");
    oiio_write(dir / "rgb_tiled_piz.exr", tiled);
    OIIO::ImageSpec parts(8, 2, 3, TypeDesc::HALF);
    parts.attribute("compression", "rle");
    oiio_write(dir / "two_parts.exr", parts, 2);
    OIIO::ImageSpec grey(8, 4, 1, TypeDesc::HALF);
    grey.channelnames = {"Y"};
    oiio_write(dir / "grey.exr", grey);
    OIIO::ImageSpec rgba(8, 4, 4, TypeDesc::HALF);
    rgba.attribute("compression", "pxr24");
    rgba.attribute("oiio:ColorSpace", "ACEScg");
    oiio_write(dir / "rgba_pxr24.exr", rgba);
    OIIO::ImageSpec data_window(8, 4, 3, TypeDesc::HALF);
    data_window.x = 2;
    data_window.y = 1;
    data_window.full_width = 12;
    data_window.full_height = 6;
    oiio_write(dir / "data_window.exr", data_window);

    oiio_write(dir / "rgb.hdr", OIIO::ImageSpec(8, 4, 3, TypeDesc::FLOAT));
    oiio_write(dir / "rgb8.png", OIIO::ImageSpec(8, 4, 3, TypeDesc::UINT8));
    oiio_write(dir / "grey_alpha16.png", OIIO::ImageSpec(8, 4, 2, TypeDesc::UINT16));
    OIIO::ImageSpec tif_tiled(16, 8, 3, TypeDesc::FLOAT);
    tif_tiled.tile_width = tif_tiled.tile_height = 16;
    oiio_write(dir / "float_tiled.tif", tif_tiled);
    OIIO::ImageSpec tif_strips(8, 4, 4, TypeDesc::UINT16);
    tif_strips.attribute("compression", "lzw");
    oiio_write(dir / "rgba16_lzw.tif", tif_strips);
    oiio_write(dir / "grey.jpg", OIIO::ImageSpec(8, 8, 1, TypeDesc::UINT8));
    oiio_write(dir / "rgb.jpg", OIIO::ImageSpec(8, 8, 3, TypeDesc::UINT8));
}

// --- image sequences -------------------------------------------------------

void sequence_seeds() {
    const fs::path dir = corpus("image_sequence");
    write_bytes(dir / "three_frames", "frame_0001.png\nframe_0002.png\nframe_0003.png\n");
    write_bytes(dir / "gap", "shot.010.exr\nshot.011.exr\nshot.013.exr\nshot.012.tif\n");
    write_bytes(dir / "other_padding", "a_01.png\na_001.png\na_02.png\na_1.png\n");
    write_bytes(dir / "single", "sky.hdr\n");
    write_bytes(dir / "later_start", "x5.png\nx3.png\nx4.png\nx6.png\n");
    write_bytes(dir / "video_name", "clip0001.mp4\nclip0002.mp4\n");
}

// --- colour maps -----------------------------------------------------------

template <typename T> void put(std::string& s, T v) { s.append(reinterpret_cast<const char*>(&v), sizeof v); }

void put_spec(std::string& s, int width, int height, double sigma_max, double mean_min, double mean_max,
              bool quadratic) {
    put<std::uint16_t>(s, std::uint16_t(width));
    put<std::uint16_t>(s, std::uint16_t(height));
    put(s, sigma_max);
    put(s, mean_min);
    put(s, mean_max);
    put<std::uint8_t>(s, quadratic ? 1 : 0);
    for (double v : {0.5, 0.1, -0.2, 0.0, 1.3, 2.0, 0.7, 1e-9}) put(s, v);  // probes: mean, sigma pairs
}

void ramp_seed(const fs::path& path, int interpolation, int mode, int hue, int flags,
               const std::vector<std::array<float, 5>>& stops) {
    std::string s;
    for (int b : {interpolation, mode, hue, flags}) put<std::uint8_t>(s, std::uint8_t(b));
    put<std::uint8_t>(s, std::uint8_t(stops.size()));
    put<std::uint16_t>(s, 64);  // dense samples
    for (const auto& stop : stops)
        for (float v : stop) put(s, v);
    for (float p : {0.0f, 0.1f, 0.25f, 0.5f, 0.6f, 0.9f, 1.0f, -0.5f}) put(s, p);
    put_spec(s, 8, 6, 0.25, 0.0, 1.0, flags & 4);
    write_bytes(path, s);
}

void colormap_seeds() {
    const fs::path ramps = corpus("color_ramp");
    const std::vector<std::array<float, 5>> two = {{0.0f, 0, 0, 0, 1}, {1.0f, 1, 1, 1, 1}};
    const std::vector<std::array<float, 5>> three = {
        {0.2f, 1, 0, 0, 1}, {0.5f, 0, 1, 0, 0.5f}, {0.8f, 0, 0, 1, 1}};
    const std::vector<std::array<float, 5>> same_place = {
        {0.5f, 1, 0.5f, 0, 1}, {0.5f, 0, 0.5f, 1, 1}, {0.9f, 2, 2, 2, 1}};
    ramp_seed(ramps / "linear_rgb_cycles", 0, 0, 0, 2, two);
    ramp_seed(ramps / "linear_rgb_exact", 0, 0, 0, 3, three);
    ramp_seed(ramps / "ease_exact", 1, 0, 0, 3, three);
    ramp_seed(ramps / "cardinal", 2, 0, 0, 2, three);
    ramp_seed(ramps / "b_spline_rgb3", 3, 0, 0, 1, three);
    ramp_seed(ramps / "constant_exact", 4, 0, 0, 3, same_place);
    ramp_seed(ramps / "constant_cycles", 4, 0, 0, 6, same_place);
    ramp_seed(ramps / "hsv_near", 0, 1, 0, 3, three);
    ramp_seed(ramps / "hsv_far", 0, 1, 1, 3, three);
    ramp_seed(ramps / "hsl_cw", 0, 2, 2, 3, three);
    ramp_seed(ramps / "hsl_ccw", 0, 2, 3, 2, three);

    const fs::path lookups = corpus("colormap_lookup");
    auto table = [](std::string& s) {  // a 3x2 RGB table image and its spec
        put<std::uint16_t>(s, 2);
        put<std::uint16_t>(s, 1);
        put<std::uint16_t>(s, 2);
        for (int i = 0; i < 18; ++i) put(s, 0.05f * float(i));
        for (double v : {0.3, 0.0, 1.0}) put(s, v);
        for (double v : {0.5, 0.1, -1.0, 0.0, 2.0, 0.5, 0.25, 0.2}) put(s, v);
    };
    {
        std::string s;  // samples: the middle row of a 4-pixel RGBA lookup image
        put<std::uint8_t>(s, 0);
        put<std::uint8_t>(s, 4);
        put<std::uint16_t>(s, 4);
        for (int i = 0; i < 16; ++i) put(s, float(i % 5) * 0.25f);
        put_spec(s, 8, 8, 0.25, 0.0, 1.0, false);
        table(s);
        write_bytes(lookups / "samples_rgba", s);
    }
    {
        std::string s;  // a single grey sample: a constant map
        put<std::uint8_t>(s, 0);
        put<std::uint8_t>(s, 1);
        put<std::uint16_t>(s, 1);
        put(s, 0.5f);
        put_spec(s, 2, 2, 1.0, -1.0, 2.0, true);
        table(s);
        write_bytes(lookups / "one_sample", s);
    }
    for (int constant : {0, 1}) {
        std::string s;  // knots with a jump (two at 0.5)
        put<std::uint8_t>(s, std::uint8_t(1 | (constant << 1)));
        put<std::uint8_t>(s, 3);
        put<std::uint16_t>(s, 4);
        for (double p : {0.0, 0.5, 0.5, 1.0}) put(s, p);
        for (int i = 0; i < 12; ++i) put(s, double(i % 4) / 3.0);
        put_spec(s, 12, 12, 0.5, -0.25, 1.25, constant);
        table(s);
        write_bytes(lookups / (constant ? "knots_constant" : "knots_linear"), s);
    }
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s <tests/fuzz folder>\n", argv[0]);
        return 2;
    }
    root = argv[1];
    visibility_seeds();
    image_seeds();
    sequence_seeds();
    colormap_seeds();
    return 0;
}
