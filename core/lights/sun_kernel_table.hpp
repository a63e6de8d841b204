// The sun kernel K(c, h) of sun_irradiance.hpp for one sun of fixed
// half-angle, tabulated for the irradiance fit, which evaluates it (with its
// slopes in c and h) for every normal × light many times per frame; the
// Blender 3.x disc's kernel costs a 32-point quadrature per call, the table
// a few multiply-adds.
//
// Inside the horizon band |c| < sin h the kernel is written
//   K(c, h) = α(h) sin h · B(t, h),  t = c / sin h = sin(πs/2),
// α(h) = K(1, h) the facing factor ((1 + cos h)/2 for the cone,
// 2 cos h/(1 + cos h) for the disc), so the band's shape B runs from 0 at
// t = −1 to 1 at t = 1 for any h. Near t = ±1 B goes as (1 ∓ t)^{5/2} (the
// sun's cap crossing the horizon), which is (1 ∓ s)^5 in s: B is tabulated
// once per model on a uniform 128 × 256 grid over s ∈ [−1, 1],
// h ∈ [0, π/2] and interpolated by Catmull–Rom cubics in both (beyond s = ±1
// the table continues as the kernel does, 0 and t; below h = 0 it mirrors, B
// being even in h). Outside the band K = α(h)·max(0, c), in closed form. The
// interpolant's own derivatives are the slopes, so the fit's Jacobian is the
// gradient of the model it minimises. Error against sun_kernel, relative to
// α(h): below 3e-5 for the cone at any h and for the disc up to h = 1.45
// (tested; 1e-6 away from the band's edges and h < 10⁻³); the disc degenerates towards h = π/2 (its radius tan h → ∞, its
// flux piling up at the rim) and the fit holds it at most `max_disc_half_angle`.
#pragma once

#include <vector>

#include "lights/frame_lights.hpp"

namespace penumbra::lights {

// The widest disc (Blender 3.x) the table is accurate for: an angle of 166°.
constexpr double max_disc_half_angle = 1.45;

struct SunKernelValue {
    double value = 0.0;        // K
    double slope = 0.0;        // ∂K/∂c
    double angle_slope = 0.0;  // ∂K/∂h
};

class TabulatedSun {
public:
    TabulatedSun(double half_angle, SunModel model);
    SunKernelValue operator()(double c) const;

private:
    SunModel model_;
    double half_ = 0.0, sin_h_ = 0.0, cot_h_ = 0.0;
    double facing_ = 0.0, facing_slope_ = 0.0;  // α(h), α'(h)
    bool point_ = false;
    // B and ∂B/∂h along t for this h, with one padding entry at each end.
    std::vector<double> shape_, shape_dh_;
};

}  // namespace penumbra::lights
