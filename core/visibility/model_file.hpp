// Files of the visibility baker: the pose model (.pzh) and the training-set
// pieces (.pvis) a render farm writes for merging.
//
// Layout (little-endian, both kinds):
//   bytes 0–7    magic "PNMBRZHM" (model) or "PNMBRVIS" (training set)
//   bytes 8–11   u32 format version: models 2 (binary16 weight blocks with a
//                float scale each, weight_blocks.hpp; version 1, float32
//                weights, is still read and rounded to blocks), training
//                sets 1
//   bytes 12–15  u32 reserved, 0
//   bytes 16–23  u64 payload size in bytes (the rest of the file)
//   bytes 24–31  u64 FNV-1a 64 checksum of the payload
//   payload      counts first (SH order, lobes, rays, vertex count, topology
//                hash, bone names as u32 length + UTF-8), then arrays, each
//                count checked against the bytes left before it is read.
// Files are written atomically (temporary + rename). A missing, truncated,
// corrupted or foreign file is a penumbra::IoError naming the file and the
// problem; nothing is executed or unpickled.
#pragma once

#include <string>

#include "visibility/pose_model.hpp"
#include "visibility/visibility_bake.hpp"

namespace penumbra::visibility {

constexpr std::uint32_t model_format_version = 2;
constexpr std::uint32_t training_format_version = 1;

void write_pose_model(const std::string& path, const PoseModel& model);
PoseModel read_pose_model(const std::string& path);

void write_training_set(const std::string& path, const TrainingSet& set);
TrainingSet read_training_set(const std::string& path);

}  // namespace penumbra::visibility
