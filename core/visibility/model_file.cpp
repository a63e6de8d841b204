#include "visibility/model_file.hpp"

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

#include "common/binary_io.hpp"
#include "common/durable_file.hpp"
#include "common/error.hpp"
#include "common/hash.hpp"

namespace penumbra::visibility {

namespace {

constexpr char model_magic[9] = "PNMBRZHM";
constexpr char training_magic[9] = "PNMBRVIS";
constexpr std::size_t header_bytes = 32;

void write_file(const std::string& path, const char* magic, std::uint32_t version, const std::string& payload) {
    std::string header(header_bytes, '\0');
    std::memcpy(header.data(), magic, 8);
    const std::uint32_t reserved = 0;
    const std::uint64_t size = payload.size(), checksum = fnv1a64(payload.data(), payload.size());
    std::memcpy(header.data() + 8, &version, 4);
    std::memcpy(header.data() + 12, &reserved, 4);
    std::memcpy(header.data() + 16, &size, 8);
    std::memcpy(header.data() + 24, &checksum, 8);
    write_file_durably(path, [&](const std::string& temporary) {
        std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
        if (!out) throw IoError("cannot create '" + temporary + "' (is the folder writable?)");
        out.write(header.data(), std::streamsize(header.size()));
        out.write(payload.data(), std::streamsize(payload.size()));
        out.flush();
        if (!out) throw IoError("cannot write '" + path + "' (disk full?)");
    });
}

// Reads the file, checks magic, version (oldest to newest, both read), size
// and checksum; returns the payload and sets version.
std::string read_payload(const std::string& path, const char* magic, const char* kind, std::uint32_t oldest,
                         std::uint32_t newest, std::uint32_t& version) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError("cannot open " + std::string(kind) + " '" + path + "': no such file or not readable");
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string prefix = "'" + path + "' is not a valid " + kind + ": ";
    if (bytes.size() < header_bytes) {
        if (bytes.size() >= 8 && std::memcmp(bytes.data(), magic, 8) == 0)
            throw IoError(prefix + "it is truncated (" + std::to_string(bytes.size()) + " bytes, no complete header)");
        throw IoError(prefix + "it is too short to be one (" + std::to_string(bytes.size()) + " bytes)");
    }
    if (std::memcmp(bytes.data(), magic, 8) != 0) {
        const bool other = std::memcmp(bytes.data(), magic == model_magic ? training_magic : model_magic, 8) == 0;
        throw IoError(prefix + (other ? "it is the other kind of Penumbra visibility file"
                                      : "wrong magic number (not a Penumbra visibility file)"));
    }
    std::uint64_t size, checksum;
    std::memcpy(&version, bytes.data() + 8, 4);
    std::memcpy(&size, bytes.data() + 16, 8);
    std::memcpy(&checksum, bytes.data() + 24, 8);
    if (version < oldest || version > newest)
        throw IoError(prefix + "format version " + std::to_string(version) + ", this build reads version " +
                      (oldest == newest ? std::to_string(newest)
                                        : std::to_string(oldest) + " to " + std::to_string(newest)) +
                      " (re-bake, or use a matching Penumbra)");
    const std::uint64_t actual = bytes.size() - header_bytes;
    if (actual < size)
        throw IoError(prefix + "it is truncated (" + std::to_string(actual) + " of " + std::to_string(size) +
                      " payload bytes)");
    if (actual > size) throw IoError(prefix + "it has " + std::to_string(actual - size) + " extra bytes at the end");
    if (fnv1a64(bytes.data() + header_bytes, size) != checksum)
        throw IoError(prefix + "checksum mismatch (the file is corrupted)");
    return bytes.substr(header_bytes);
}

}  // namespace

void write_pose_model(const std::string& path, const PoseModel& model) {
    check_pose_model(model);
    BinaryWriter w;
    w.put(std::uint32_t(model.order));
    w.put(std::uint32_t(model.lobes));
    w.put(std::uint32_t(model.rays));
    w.put(std::uint32_t(model.below_horizon));
    w.put(std::uint32_t(model.features));
    w.put(std::uint64_t(model.vertex_count));
    w.put(std::uint64_t(model.topology_hash));
    w.put_strings(model.armature_bones);
    w.put_strings(model.joints);
    w.put(std::uint32_t(model.summary.size()));
    for (const auto& [key, value] : model.summary) {
        w.put_string(key);
        w.put(value);
    }
    w.put_array(model.joint_offsets);
    w.put(std::uint64_t(model.joint_index.size()));
    w.put_array(model.joint_index);
    w.put_array(model.bias);
    w.put_array(model.feature_offsets);
    w.put_array(model.feature_basis);
    w.put_array(model.block_directions);
    w.put_array(model.weight_scales);
    w.put_array(model.weights);
    write_file(path, model_magic, model_format_version, w.bytes());
}

PoseModel read_pose_model(const std::string& path) {
    std::uint32_t version = 0;
    const std::string payload = read_payload(path, model_magic, "Penumbra pose model", 1, model_format_version, version);
    BinaryReader r(path, "Penumbra visibility file", payload.data(), payload.size());
    PoseModel m;
    m.order = int(r.get<std::uint32_t>());
    m.lobes = int(r.get<std::uint32_t>());
    m.rays = int(r.get<std::uint32_t>());
    const auto below = r.get<std::uint32_t>();
    const auto features = r.get<std::uint32_t>();
    if (m.order < 1 || m.order > max_sh_order || m.lobes < 1 || m.lobes > max_lobes || below > 1 || features > 1)
        r.fail("order, lobes or kinds out of range");
    m.below_horizon = BelowHorizon(below);
    m.features = PoseFeatures(features);
    m.vertex_count = r.get<std::uint64_t>();
    m.topology_hash = r.get<std::uint64_t>();
    m.armature_bones = r.get_strings(65535);
    m.joints = r.get_strings(65535);
    const auto n_summary = r.get<std::uint32_t>();
    if (n_summary > 1024) r.fail("too many summary entries");
    for (std::uint32_t i = 0; i < n_summary; ++i) {
        std::string key = r.get_string();
        m.summary.emplace_back(std::move(key), r.get<double>());
    }
    if (m.vertex_count >= payload.size()) r.fail("vertex count larger than the file could hold");
    m.joint_offsets = r.get_array<std::uint32_t>(m.vertex_count + 1, "the joint offsets");
    const auto nnz = r.get<std::uint64_t>();
    m.joint_index = r.get_array<std::uint16_t>(nnz, "the joint indices");
    const std::uint64_t d = std::uint64_t(m.params_per_vertex());
    m.bias = r.get_array<float>(m.vertex_count * d, "the constant terms");
    const std::uint64_t fpj = features_per_joint(m.features);
    try {
        if (version == 1) {  // float32 weights of the raw joint features, before binary16 blocks
            const std::vector<float> weights = r.get_array<float>(nnz * fpj * d, "the joint weights");
            r.expect_end();
            for (float x : weights)
                if (!std::isfinite(x)) r.fail("model has a non-finite value");
            use_raw_joint_features(m);
            set_weights(m, weights);
        } else {
            m.feature_offsets = r.get_array<std::uint32_t>(m.joints.size() + 1, "the joint feature offsets");
            if (m.feature_offsets.front() != 0) r.fail("joint feature offsets do not start at 0");
            for (std::size_t j = 0; j < m.joints.size(); ++j)
                if (m.feature_offsets[j + 1] < m.feature_offsets[j] || m.feature_offsets[j + 1] - m.feature_offsets[j] > fpj)
                    r.fail("joint feature counts out of range");
            m.feature_basis = r.get_array<float>(m.feature_offsets.back() * fpj, "the joint feature directions");
            m.block_directions = r.get_array<std::uint8_t>(nnz, "the block directions");
            m.weight_scales = r.get_array<float>(nnz, "the weight scales");
            index_weight_blocks(m);
            m.weights = r.get_array<std::uint16_t>(m.weight_offsets.back(), "the joint weights");
            r.expect_end();
        }
    } catch (const ArgumentError& e) {
        r.fail(e.what());
    }
    try {
        check_pose_model(m);
    } catch (const ArgumentError& e) {
        r.fail(e.what());
    }
    return m;
}

void write_training_set(const std::string& path, const TrainingSet& set) {
    check_training_set(set);
    BinaryWriter w;
    w.put(std::uint32_t(set.settings.order));
    w.put(std::uint32_t(set.settings.rays));
    w.put(std::uint32_t(set.settings.below_horizon));
    w.put(std::uint32_t(set.settings.weighting));
    w.put(set.settings.offset_scale);
    w.put(std::uint64_t(set.vertex_count));
    w.put(std::uint64_t(set.topology_hash));
    w.put_strings(set.bone_names);
    w.put(std::uint32_t(set.frames.size()));
    for (const auto& f : set.frames) {
        w.put(f.frame);
        w.put_array(f.bone_rotations);
        w.put_array(f.visibility);
    }
    write_file(path, training_magic, training_format_version, w.bytes());
}

TrainingSet read_training_set(const std::string& path) {
    std::uint32_t version = 0;
    const std::string payload = read_payload(path, training_magic, "Penumbra visibility training set",
                                             training_format_version, training_format_version, version);
    BinaryReader r(path, "Penumbra visibility file", payload.data(), payload.size());
    TrainingSet s;
    s.settings.order = int(r.get<std::uint32_t>());
    s.settings.rays = int(r.get<std::uint32_t>());
    const auto below = r.get<std::uint32_t>(), weighting = r.get<std::uint32_t>();
    if (below > 1 || weighting > 1) r.fail("ray rules out of range");
    s.settings.below_horizon = BelowHorizon(below);
    s.settings.weighting = Weighting(weighting);
    s.settings.offset_scale = r.get<double>();
    try {
        check_bake_settings(s.settings);
    } catch (const ArgumentError& e) {
        r.fail(e.what());
    }
    s.vertex_count = r.get<std::uint64_t>();
    s.topology_hash = r.get<std::uint64_t>();
    s.bone_names = r.get_strings(65535);
    const auto n_frames = r.get<std::uint32_t>();
    const std::uint64_t n_sh = std::uint64_t(s.settings.order) * s.settings.order;
    if (s.vertex_count >= payload.size()) r.fail("vertex count larger than the file could hold");
    for (std::uint32_t i = 0; i < n_frames; ++i) {
        TrainingFrame f;
        f.frame = r.get<double>();
        f.bone_rotations = r.get_array<float>(9 * std::uint64_t(s.bone_names.size()), "a frame's bone rotations");
        f.visibility = r.get_array<float>(s.vertex_count * n_sh, "a frame's visibility");
        s.frames.push_back(std::move(f));
    }
    r.expect_end();
    try {
        check_training_set(s);
    } catch (const ArgumentError& e) {
        r.fail(e.what());
    }
    return s;
}

}  // namespace penumbra::visibility
