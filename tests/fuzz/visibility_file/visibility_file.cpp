// Fuzz harness: the visibility baker's files, the pose model (.pzh) and the
// training-set pieces a render farm writes (.pvis), as read by
// core/visibility/model_file.cpp, and what run time and merging do with a
// file that was accepted.
//
// Input: the file's bytes. When they start with either magic number and the
// header's reserved field (bytes 12-15, which the reader ignores) is 0, the
// harness first writes the true payload size and FNV-1a checksum into the
// header, so mutations reach the payload parser instead of all stopping at
// the checksum; a non-zero reserved field leaves the header as it is, which
// fuzzes the header checks. Checked beyond "only penumbra::Error":
//   - an accepted model drives synthesize_params + lobes_from_params;
//   - an accepted file written back reads back identical;
//   - an accepted training set merged with itself has strictly ascending frames.
#include <cmath>
#include <cstring>

#include "../fuzz_util.hpp"
#include "visibility/mesh_frames.hpp"
#include "visibility/model_file.hpp"
#include "visibility/pose_model.hpp"

using namespace penumbra;
using namespace penumbra::visibility;

namespace {

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

void check_model(const PoseModel& m, const std::string& path) {
    const std::size_t d = std::size_t(m.params_per_vertex());
    std::vector<float> rotations(9 * m.joints.size(), 0.0f);
    for (std::size_t j = 0; j < m.joints.size(); ++j)
        rotations[9 * j] = rotations[9 * j + 4] = rotations[9 * j + 8] = 1.0f;
    std::vector<float> params(m.vertex_count * d), axes(m.vertex_count * m.lobes * 3),
        bands(m.vertex_count * m.lobes * m.order);
    synthesize_params(m, rotations.data(), params.data(), 1);
    lobes_from_params(m.order, m.lobes, m.vertex_count, params.data(), axes.data(), bands.data());

    const std::string again = path + ".again.pzh";
    write_pose_model(again, m);
    const PoseModel r = read_pose_model(again);
    penumbra_fuzz_check(r.order == m.order && r.lobes == m.lobes && r.rays == m.rays &&
                            r.below_horizon == m.below_horizon && r.features == m.features &&
                            r.vertex_count == m.vertex_count && r.topology_hash == m.topology_hash &&
                            r.armature_bones == m.armature_bones && r.joints == m.joints &&
                            r.joint_offsets == m.joint_offsets && r.joint_index == m.joint_index &&
                            same_bits(r.bias, m.bias) && r.weights == m.weights && same_bits(r.weight_scales, m.weight_scales) &&
                            r.block_directions == m.block_directions && r.feature_offsets == m.feature_offsets &&
                            same_bits(r.feature_basis, m.feature_basis) &&
                            r.summary.size() == m.summary.size(),
                        "a pose model written back does not read back the same");
}

void check_training_set_file(const TrainingSet& s, const std::string& path) {
    const std::string again = path + ".again.pvis";
    write_training_set(again, s);
    const TrainingSet r = read_training_set(again);
    penumbra_fuzz_check(r.vertex_count == s.vertex_count && r.topology_hash == s.topology_hash &&
                            r.bone_names == s.bone_names && r.frames.size() == s.frames.size() &&
                            r.settings.order == s.settings.order && r.settings.rays == s.settings.rays,
                        "a training set written back does not read back the same");
    for (std::size_t i = 0; i < s.frames.size(); ++i)
        penumbra_fuzz_check(same_bits(r.frames[i].visibility, s.frames[i].visibility) &&
                                same_bits(r.frames[i].bone_rotations, s.frames[i].bone_rotations),
                            "a training frame written back does not read back the same");

    const TrainingSet merged = merge_training_sets({s, r});
    for (std::size_t i = 1; i < merged.frames.size(); ++i)
        penumbra_fuzz_check(merged.frames[i - 1].frame < merged.frames[i].frame,
                            "merged training frames are not in strictly ascending order");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::string bytes(reinterpret_cast<const char*>(data), size);
    const bool model = size >= 8 && std::memcmp(data, "PNMBRZHM", 8) == 0;
    const bool training = size >= 8 && std::memcmp(data, "PNMBRVIS", 8) == 0;
    std::uint32_t reserved = 1;
    if (size >= 32) std::memcpy(&reserved, data + 12, 4);
    if ((model || training) && reserved == 0) {
        const std::uint64_t payload = size - 32, checksum = fnv1a64(bytes.data() + 32, payload);
        std::memcpy(bytes.data() + 16, &payload, 8);
        std::memcpy(bytes.data() + 24, &checksum, 8);
    }
    fuzz::Scratch::get().fresh();
    const std::string path = fuzz::Scratch::get().file(training ? "input.pvis" : "input.pzh");
    fuzz::write_file(path, bytes.data(), bytes.size());
    if (!training)
        fuzz::expect_only_penumbra_errors([&] { check_model(read_pose_model(path), path); });
    if (!model)
        fuzz::expect_only_penumbra_errors([&] { check_training_set_file(read_training_set(path), path); });
    return 0;
}
