// Blender's world directions and its equirectangular (latitude–longitude)
// images: the one place the convention is written down. The SH engine
// (sh/projection.hpp) and the light-rig tool (lights/mapping.hpp,
// lights/environment.hpp, lights/sampling.cpp) all call these functions.
// Tests: tests/cpp/common/latlong_test.cpp.
//
// World directions
// ------------------------------------------------------------------------
// Blender world coordinates: right-handed, +z up. A direction is a unit
// vector pointing from the scene towards what is seen there (the sky, a
// light). Its polar angle θ ∈ [0, π] is measured from +z and its azimuth
// φ = atan2(y, x) from +x towards +y:
//   d = (sinθ cosφ, sinθ sinφ, cosθ).
//
// Equirectangular images (World > Environment Texture, default Vector = the
// view direction, default mapping)
// ------------------------------------------------------------------------
// Cycles maps a world direction d = (x, y, z) to image coordinates
//   u = 0.5 − atan2(y, x) / 2π,   v = 1 − acos(z) / π
// (intern/cycles/kernel/camera/projection.h: direction_to_equirectangular =
// direction_to_equirectangular_range(dir, (−2π, π, −π, π)); used by
// svm_node_tex_environment in intern/cycles/kernel/svm/image.h), where v = 0
// is the first row of Blender's pixel buffer, which is stored bottom-up
// (intern/cycles/scene/image_oiio.cpp reads the file with a negative
// scanline stride). So for a W×H image as OpenImageIO returns it (row 0 =
// top row of the file), in continuous pixel coordinates (x to the right,
// y down, pixel (row r, column c) covering [c, c+1) × [r, r+1)):
//   θ = π y / H          (θ from +z: row 0 is straight up)
//   φ = π − 2π x / W     (φ = atan2(y, x))
// and pixel (r, c) covers θ ∈ [π r/H, π (r+1)/H], φ ∈ [π − 2π (c+1)/W,
// π − 2π c/W]; its centre (x, y) = (c + ½, r + ½) looks along the d above.
// Landmarks: the image centre faces +x; the left edge (and right edge) −x;
// the column a quarter from the left faces +y, three quarters −y; the top
// row is +z (up), the bottom row −z. Moving right in the image turns from +x
// towards −y, i.e. clockwise seen from above, as when standing inside the
// sphere looking out.
//
// Every function below takes an image position and size row first, as the
// pixel buffer is stored (row-major, numpy's shape (H, W)): (row or y,
// column or x, height, width).
//
// Upper-hemisphere maps (the light-rig paper's 360×90 "polar projection")
// are the top half of a full map: the same φ, θ = (π/2) y / H, the bottom row
// is the horizon. Every function below takes the θ range as theta_max:
// full_sphere (π, the default) or upper_hemisphere (π/2).
//
// Solid angle of a pixel in row r (the exact integral of sinθ dθ dφ, the
// Jacobian every sampler and projection uses):
//   Δφ (cos θ_top − cos θ_bottom),   Δφ = 2π / W.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Core>

namespace penumbra::latlong {

constexpr double full_sphere = std::numbers::pi;             // θ ∈ [0, π]
constexpr double upper_hemisphere = 0.5 * std::numbers::pi;  // θ ∈ [0, π/2]

// ---- World directions ----

inline Eigen::Vector3d direction_of_angles(double theta, double phi) {
    const double s = std::sin(theta);
    return {s * std::cos(phi), s * std::sin(phi), std::cos(theta)};
}

// θ and φ of a unit direction (z is clamped to [−1, 1] against rounding;
// φ ∈ [−π, π], 0 on the z axis).
inline double theta_of_direction(const Eigen::Vector3d& d) { return std::acos(std::clamp(d.z(), -1.0, 1.0)); }
inline double phi_of_direction(const Eigen::Vector3d& d) { return std::atan2(d.y(), d.x()); }

// ---- Image coordinates ↔ angles ----

// Azimuth of continuous column coordinate x of a W-wide image.
inline double phi_of_x(double x, int width) { return std::numbers::pi - 2.0 * std::numbers::pi * x / width; }

// Column coordinate x ∈ [0, W) of azimuth φ (any real φ, wrapped; φ = ±π
// both land on x = 0, the left edge). Rounding can give x = W for φ just
// below π; callers that index pixels clamp.
inline double x_of_phi(double phi, int width) {
    const double u = 0.5 - phi / (2.0 * std::numbers::pi);
    return (u - std::floor(u)) * width;
}

// Polar angle of continuous row coordinate y of an H-high image.
inline double theta_of_y(double y, int height, double theta_max = full_sphere) { return theta_max * y / height; }

// ---- Image coordinates ↔ directions ----

// Direction of continuous pixel position (row coordinate y, column
// coordinate x).
inline Eigen::Vector3d direction_at(double y, double x, int height, int width, double theta_max = full_sphere) {
    return direction_of_angles(theta_of_y(y, height, theta_max), phi_of_x(x, width));
}

// Direction of the centre of pixel (row, column).
inline Eigen::Vector3d pixel_direction(int row, int column, int height, int width, double theta_max = full_sphere) {
    return direction_at(row + 0.5, column + 0.5, height, width, theta_max);
}

// Exact solid angle of any pixel in `row`: Δφ (cos θ_top − cos θ_bottom).
inline double pixel_solid_angle(int row, int height, int width, double theta_max = full_sphere) {
    return (2.0 * std::numbers::pi / width) *
           (std::cos(theta_of_y(row, height, theta_max)) - std::cos(theta_of_y(row + 1.0, height, theta_max)));
}

}  // namespace penumbra::latlong
