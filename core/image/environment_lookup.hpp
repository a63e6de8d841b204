// Blender's Environment Texture as Cycles looks it up, and the World that a
// sum of such textures and colours lights, resampled onto a latlong grid:
// the light rig's source map and the SH lighting's input whenever the World
// is more than one rotated latlong image. addon/penumbra/world.py reads the
// node tree into EnvironmentTerms; the grid follows common/latlong.hpp.
//
// The lookup (Cycles: svm_node_tex_environment, kernel/svm/image.h). The
// view direction d goes through the Vector's steps x ↦ A·x + b (Mapping and
// Vector Rotate nodes, in the order they act), a step optionally followed by
// a normalization (a NORMAL Mapping), then m = safe_normalize(x), 0 when x is
// 0. (u, v) = direction_to_equirectangular(m) or direction_to_mirrorball(m)
// (kernel/camera/projection.h), v = 0 the bottom row of Blender's buffer.
// The image repeats on both axes (EnvironmentTextureNode::image_params);
// Closest reads pixel floor(u·W, v·H), every other interpolation is read
// bilinearly about pixel centres (Cubic and Smart too: an approximation).
// u·W and v·H are rounded to float, as Cycles computes them.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "common/progress.hpp"
#include "image/image.hpp"

namespace penumbra {

enum class EnvironmentProjection { equirectangular, mirror_ball };

struct LookupStep {
    Eigen::Matrix3d a = Eigen::Matrix3d::Identity();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    bool normalize = false;  // safe_normalize after the affine map (a NORMAL Mapping)
};

// One Background's share of the World: scale · (colour, or the image looked up).
struct EnvironmentTerm {
    double scale = 1.0;                           // its mix weight × its Strength
    Eigen::Vector3d colour = Eigen::Vector3d::Zero();  // a uniform term (image == nullptr)
    const Image* image = nullptr;                 // RGB(A), row 0 = the top; alpha ignored
    EnvironmentProjection projection = EnvironmentProjection::equirectangular;
    bool closest = false;
    std::vector<LookupStep> steps;                // in the order they act on d
};

// m for view direction d: the steps, then safe_normalize (0 when the vector is 0).
Eigen::Vector3d lookup_direction(const std::vector<LookupStep>& steps, const Eigen::Vector3d& d);

// The image's RGB at lookup direction m (unit, or 0), as Cycles reads it.
Eigen::Vector3f texture_lookup(const Image& image, const Eigen::Vector3d& m, EnvironmentProjection projection,
                               bool closest);

// (width/2, width, 3): Σ over terms of scale·value(m(d)) on the latlong grid
// of world directions d; each cell is the solid-angle-weighted mean of
// supersampling² lookups at its sub-cell centres (weights ∝ sin θ of the
// sub-row), as the core resamples a fisheye or a mirror ball. Uniform terms
// add their colour to every cell. NaN and Inf pixels pass through (the
// caller counts and reports them). ArgumentError for a width below 2,
// supersampling below 1, an empty image or one with fewer than 3 channels,
// or a non-finite scale, colour or step. Parallel over rows; progress and
// cancel as common/parallel.hpp says.
Image environment_radiance(const std::vector<EnvironmentTerm>& terms, int width, int supersampling = 2,
                           int threads = 0, const Progress& progress = Progress());

}  // namespace penumbra
