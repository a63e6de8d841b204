// How an environment image maps to directions in Blender world coordinates
// (common/latlong.hpp: +z up, pointing FROM the scene TOWARDS the light, as
// in core/sh), for every input the light-rig tool accepts.
//
// Projections (continuous pixel coordinates: x to the right, y down, pixel
// (column c, row r) covers [c, c+1) × [r, r+1), row 0 = top row of the file)
// ------------------------------------------------------------------------
// equirectangular   the full sphere in Blender's World convention
//                   (common/latlong.hpp, the one place it is written down).
// hemisphere_polar  the upper hemisphere only, as the paper's 360×90 "polar
//                   projection": the top half of an equirectangular map
//                   (latlong::upper_hemisphere); the bottom row is the horizon.
// fisheye           a circular fisheye looking straight up (+z): the image
//                   circle is the largest circle centred in the image
//                   (radius R = min(W, H)/2), its rim the horizon. The top of
//                   the image faces +y, the right −x (as seen looking up from
//                   below, east on the left like a sky chart). Radius ρ ∈ [0, 1]
//                   (in units of R) and zenith angle θ follow the
//                   Kannala–Brandt / OpenCV fisheye model
//                     ρ(θ) = d(θ) / d(π/2),  d(θ) = θ (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸),
//                   so k = 0 is the equidistant (f·θ) lens of the paper.
// mirror_ball       a photograph of a mirrored sphere filling the inscribed
//                   circle, taken by a distant camera looking along +y (the
//                   camera is on the −y side): the ball's centre reflects −y
//                   (back to the camera), its rim +y (behind the ball), the
//                   image top +z and right +x. A point at normalized (u, v)
//                   (right, up) has normal n = (u, −√(1−u²−v²), v) and
//                   reflects r = c − 2(c·n)n with c = (0, 1, 0).
//
// Solid angle per pixel (the Jacobians the PDF uses):
//   equirectangular / polar   Δφ (cos θ_top − cos θ_bottom)   (the paper's sin θ;
//                             latlong::pixel_solid_angle)
//   fisheye                   sin θ · (dθ/dρ) / ρ · (1/R²)
//   mirror_ball               4 / R²  (dΩ = 4 dA in units of the ball radius)
#pragma once

#include <array>

#include <Eigen/Core>

namespace penumbra::lights {

enum class Projection { equirectangular, hemisphere_polar, fisheye, mirror_ball };

const char* projection_name(Projection projection);

// Kannala–Brandt coefficients k1..k4 of a fisheye lens (all 0: equidistant).
// ρ(θ) must increase on [0, π/2]; FisheyeLens::check throws ArgumentError
// when it does not.
struct FisheyeLens {
    std::array<double, 4> k{0.0, 0.0, 0.0, 0.0};
    double distortion(double theta) const;           // d(θ)
    double distortion_derivative(double theta) const;  // d'(θ)
    void check() const;
    // Zenith angle θ ∈ [0, π/2] for normalized radius ρ ∈ [0, 1] (Newton on d).
    double theta_of_radius(double rho) const;
};

// Whether a projection covers the full sphere (else the upper hemisphere).
bool covers_full_sphere(Projection projection);

// Whether a projection is a latitude–longitude grid (equirectangular or
// hemisphere_polar), which the working grid keeps as it is.
bool is_latlong(Projection projection);

// Direction of continuous pixel position (x, y) of a width×height image, or
// false if it lies outside the image circle (fisheye, mirror ball). The
// direction is a unit vector.
bool image_to_direction(Projection projection, const FisheyeLens& lens, int width, int height, double x, double y,
                        Eigen::Vector3d& direction);

// Continuous pixel position of a direction, or false when the projection does
// not show it (the lower hemisphere for fisheye and polar).
bool direction_to_image(Projection projection, const FisheyeLens& lens, int width, int height,
                        const Eigen::Vector3d& direction, double& x, double& y);

// Solid angle of pixel (column, row) (0 for a pixel whose centre is outside
// the image circle): the Jacobians listed above, evaluated at the centre for
// fisheye and mirror ball, exact for the two latitude–longitude maps.
double pixel_solid_angle(Projection projection, const FisheyeLens& lens, int width, int height, int column, int row);

}  // namespace penumbra::lights
