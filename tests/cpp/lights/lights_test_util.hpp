// Synthetic environment maps with known integrals and irradiance, and
// random light sets.
#pragma once

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "image/image.hpp"
#include "lights/environment.hpp"
#include "lights/frame_lights.hpp"

namespace penumbra::lights::testing {

inline Image constant_image(int w, int h, float r, float g, float b) {
    Image im(w, h, 3);
    for (std::size_t i = 0; i < im.pixel_count(); ++i) {
        im.pixels[3 * i] = r;
        im.pixels[3 * i + 1] = g;
        im.pixels[3 * i + 2] = b;
    }
    return im;
}

// Equirectangular sky (radiance `sky`) plus a sun disc of angular radius
// `radius` around `sun` with radiance `sun_radiance` (cell centres inside).
inline Image sky_and_sun(int w, int h, double sky, const Eigen::Vector3d& sun, double radius, double sun_radiance) {
    Image im(w, h, 3);
    const double pi = std::numbers::pi;
    for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c) {
            const double theta = pi * (r + 0.5) / h, phi = pi - 2 * pi * (c + 0.5) / w;
            const Eigen::Vector3d d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
            const double v = d.dot(sun.normalized()) >= std::cos(radius) ? sun_radiance : sky;
            for (int ch = 0; ch < 3; ++ch) im.at(c, r, ch) = float(v);
        }
    return im;
}

inline EnvironmentMap as_map(const Image& im, Projection p = Projection::equirectangular) {
    MapOptions o;
    o.projection = p;
    o.max_width = 0;
    return make_environment(im, o);
}

// n lights in uniformly random directions with powers in [0.1, 2), grey.
inline std::vector<Light> random_lights(int n, unsigned seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> g(0.0, 1.0);
    std::uniform_real_distribution<double> p(0.1, 2.0);
    std::vector<Light> lights(n);
    for (int i = 0; i < n; ++i) {
        lights[i].index = i;
        lights[i].direction = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
        lights[i].power = p(rng);
        lights[i].rgb = Eigen::Vector3d::Constant(lights[i].power);
    }
    return lights;
}

}  // namespace penumbra::lights::testing
