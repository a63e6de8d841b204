#include "lights/mapping.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <string>

#include "common/error.hpp"
#include "common/latlong.hpp"
#include "common/math.hpp"

namespace penumbra::lights {
namespace {

constexpr double pi = std::numbers::pi;

// θ range of the two latitude–longitude projections.
double latlong_theta_max(Projection projection) {
    return projection == Projection::equirectangular ? latlong::full_sphere : latlong::upper_hemisphere;
}

// Normalized image-circle coordinates (u right, v up, in units of R).
void to_circle(int width, int height, double x, double y, double& u, double& v) {
    const double r = 0.5 * std::min(width, height);
    u = (x - 0.5 * width) / r;
    v = (0.5 * height - y) / r;
}

void from_circle(int width, int height, double u, double v, double& x, double& y) {
    const double r = 0.5 * std::min(width, height);
    x = 0.5 * width + u * r;
    y = 0.5 * height - v * r;
}

}  // namespace

const char* projection_name(Projection projection) {
    switch (projection) {
    case Projection::equirectangular: return "equirectangular";
    case Projection::hemisphere_polar: return "hemisphere_polar";
    case Projection::fisheye: return "fisheye";
    case Projection::mirror_ball: return "mirror_ball";
    }
    return "?";
}

double FisheyeLens::distortion(double t) const {
    const double t2 = t * t;
    return t * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
}

double FisheyeLens::distortion_derivative(double t) const {
    const double t2 = t * t;
    return 1.0 + t2 * (3 * k[0] + t2 * (5 * k[1] + t2 * (7 * k[2] + t2 * 9 * k[3])));
}

void FisheyeLens::check() const {
    for (double c : k)
        if (!std::isfinite(c)) throw ArgumentError("fisheye lens coefficients must be finite");
    // d'(θ) > 0 on [0, π/2] keeps the radius ↔ angle map one-to-one.
    for (int i = 0; i <= 256; ++i)
        if (distortion_derivative(0.5 * pi * i / 256) <= 0.0)
            throw ArgumentError("fisheye lens coefficients give a radius that does not grow with the angle "
                                "from the zenith; check k1..k4 (Kannala–Brandt / OpenCV fisheye model)");
}

double FisheyeLens::theta_of_radius(double rho) const {
    const double rim = distortion(0.5 * pi);
    const double target = std::clamp(rho, 0.0, 1.0) * rim;
    double t = 0.5 * pi * std::clamp(rho, 0.0, 1.0);  // the equidistant answer
    for (int i = 0; i < 30; ++i) {
        const double step = (distortion(t) - target) / distortion_derivative(t);
        t = std::clamp(t - step, 0.0, 0.5 * pi);
        if (std::abs(step) < 1e-14) break;
    }
    return t;
}

bool covers_full_sphere(Projection projection) {
    return projection == Projection::equirectangular || projection == Projection::mirror_ball;
}

bool is_latlong(Projection projection) {
    return projection == Projection::equirectangular || projection == Projection::hemisphere_polar;
}

bool image_to_direction(Projection projection, const FisheyeLens& lens, int width, int height, double x, double y,
                        Eigen::Vector3d& direction) {
    switch (projection) {
    case Projection::equirectangular:
    case Projection::hemisphere_polar:
        direction = latlong::direction_at(y, x, height, width, latlong_theta_max(projection));
        return true;
    case Projection::fisheye: {
        double u, v;
        to_circle(width, height, x, y, u, v);
        const double rho = length_2d(u, v);
        if (rho > 1.0) return false;
        const double theta = lens.theta_of_radius(rho);
        const double s = std::sin(theta);
        // Image right is −x, image up is +y (looking up from below).
        direction = rho > 0.0 ? Eigen::Vector3d(-u / rho * s, v / rho * s, std::cos(theta))
                              : Eigen::Vector3d(0.0, 0.0, 1.0);
        return true;
    }
    case Projection::mirror_ball: {
        double u, v;
        to_circle(width, height, x, y, u, v);
        const double rho2 = u * u + v * v;
        if (rho2 > 1.0) return false;
        const Eigen::Vector3d n(u, -std::sqrt(std::max(0.0, 1.0 - rho2)), v);
        const Eigen::Vector3d c(0.0, 1.0, 0.0);
        direction = (c - 2.0 * c.dot(n) * n).normalized();
        return true;
    }
    }
    return false;
}

bool direction_to_image(Projection projection, const FisheyeLens& lens, int width, int height,
                        const Eigen::Vector3d& d, double& x, double& y) {
    const double theta = latlong::theta_of_direction(d);
    switch (projection) {
    case Projection::equirectangular:
    case Projection::hemisphere_polar: {
        x = latlong::x_of_phi(latlong::phi_of_direction(d), width);
        const double theta_max = latlong_theta_max(projection);
        if (theta > theta_max + 1e-12) return false;
        y = std::min(theta / theta_max, 1.0) * height;
        return true;
    }
    case Projection::fisheye: {
        if (theta > 0.5 * pi + 1e-12) return false;
        const double rho = lens.distortion(std::min(theta, 0.5 * pi)) / lens.distortion(0.5 * pi);
        const double s = length_2d(d.x(), d.y());
        const double u = s > 0.0 ? -d.x() / s * rho : 0.0;
        const double v = s > 0.0 ? d.y() / s * rho : 0.0;
        from_circle(width, height, u, v, x, y);
        return true;
    }
    case Projection::mirror_ball: {
        // The normal halves the angle between the reflected ray and −c.
        const Eigen::Vector3d h = d.normalized() - Eigen::Vector3d(0.0, 1.0, 0.0);
        const double len = h.norm();
        if (len < 1e-12) {  // straight behind the ball: the whole rim
            from_circle(width, height, 0.0, 1.0, x, y);
            return true;
        }
        const Eigen::Vector3d n = h / len;
        from_circle(width, height, n.x(), n.z(), x, y);
        return true;
    }
    }
    return false;
}

double pixel_solid_angle(Projection projection, const FisheyeLens& lens, int width, int height, int column, int row) {
    switch (projection) {
    case Projection::equirectangular:
    case Projection::hemisphere_polar:
        return latlong::pixel_solid_angle(row, height, width, latlong_theta_max(projection));
    case Projection::fisheye: {
        double u, v;
        to_circle(width, height, column + 0.5, row + 0.5, u, v);
        const double rho = length_2d(u, v);
        if (rho > 1.0) return 0.0;
        const double r = 0.5 * std::min(width, height);
        const double rim = lens.distortion(0.5 * pi);
        // ρ = d(θ)/d(π/2)  →  dθ/dρ = d(π/2) / d'(θ); sinθ/ρ → 1/(dρ/dθ) at ρ = 0.
        const double theta = lens.theta_of_radius(rho);
        const double dtheta_drho = rim / lens.distortion_derivative(theta);
        const double sin_over_rho = rho > 1e-9 ? std::sin(theta) / rho : dtheta_drho;
        return sin_over_rho * dtheta_drho / (r * r);
    }
    case Projection::mirror_ball: {
        double u, v;
        to_circle(width, height, column + 0.5, row + 0.5, u, v);
        if (u * u + v * v > 1.0) return 0.0;
        const double r = 0.5 * std::min(width, height);
        return 4.0 / (r * r);
    }
    }
    return 0.0;
}

}  // namespace penumbra::lights
