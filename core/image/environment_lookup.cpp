#include "image/environment_lookup.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "common/error.hpp"
#include "common/latlong.hpp"
#include "common/parallel.hpp"

namespace penumbra {

namespace {

Eigen::Vector3d safe_normalize(const Eigen::Vector3d& v) {
    const double length = v.norm();
    return length > 0.0 ? Eigen::Vector3d(v / length) : Eigen::Vector3d::Zero();
}

// (u, v) of Cycles' direction_to_equirectangular / direction_to_mirrorball,
// v = 0 at the bottom.
Eigen::Vector2d texture_coordinates(const Eigen::Vector3d& m, EnvironmentProjection projection) {
    if (projection == EnvironmentProjection::mirror_ball) {
        // The ball's normal halfway between the view back to the camera (−y) and m.
        const double y = m.y() - 1.0;
        double div = 2.0 * std::sqrt(std::max(-0.5 * y, 0.0));
        if (!(div > 0.0)) div = 1.0;
        return {0.5 * (m.x() / div + 1.0), 0.5 * (m.z() / div + 1.0)};
    }
    return {0.5 - std::atan2(m.y(), m.x()) / (2.0 * std::numbers::pi),
            1.0 - std::acos(std::clamp(m.z(), -1.0, 1.0)) / std::numbers::pi};
}

// Blender's pixel (column, row from the bottom), both wrapped: the texture repeats.
Eigen::Vector3f pixel(const Image& image, long column, long row) {
    const long w = image.width, h = image.height;
    column = ((column % w) + w) % w;
    row = ((row % h) + h) % h;
    const float* p = image.row(int(h - 1 - row)) + column * image.channels;
    return {p[0], p[1], p[2]};
}

void check_term(const EnvironmentTerm& term) {
    if (!std::isfinite(term.scale) || !term.colour.allFinite())
        throw ArgumentError("an environment term's scale and colour must be finite");
    for (const LookupStep& step : term.steps)
        if (!step.a.allFinite() || !step.b.allFinite())
            throw ArgumentError("an environment lookup step must be finite");
    if (term.image && (term.image->empty() || term.image->channels < 3))
        throw ArgumentError("an environment image must have pixels and at least 3 channels, got " +
                            std::to_string(term.image->width) + "x" + std::to_string(term.image->height) + "x" +
                            std::to_string(term.image->channels));
}

// One grid row: each cell the sin θ-weighted mean of k × k lookups.
void radiance_row(const std::vector<EnvironmentTerm>& terms, int row, int width, int k, Image& out) {
    const int height = out.height;
    std::vector<double> cells(static_cast<std::size_t>(width) * 3, 0.0);
    double weight_sum = 0.0;
    for (int i = 0; i < k; ++i) {
        const double y = row + (i + 0.5) / k;
        const double weight = std::sin(latlong::theta_of_y(y, height));
        weight_sum += weight;
        for (int c = 0; c < width; ++c)
            for (int j = 0; j < k; ++j) {
                const Eigen::Vector3d d = latlong::direction_at(y, c + (j + 0.5) / k, height, width);
                for (const EnvironmentTerm& term : terms) {
                    if (!term.image) continue;
                    const Eigen::Vector3f value =
                        texture_lookup(*term.image, lookup_direction(term.steps, d), term.projection, term.closest);
                    for (int ch = 0; ch < 3; ++ch) cells[3 * c + ch] += weight * term.scale * value[ch];
                }
            }
    }
    Eigen::Vector3d uniform = Eigen::Vector3d::Zero();
    for (const EnvironmentTerm& term : terms)
        if (!term.image) uniform += term.scale * term.colour;
    float* dst = out.row(row);
    for (int c = 0; c < width; ++c)
        for (int ch = 0; ch < 3; ++ch)
            dst[3 * c + ch] = float(cells[3 * c + ch] / (k * weight_sum) + uniform[ch]);
}

}  // namespace

Eigen::Vector3d lookup_direction(const std::vector<LookupStep>& steps, const Eigen::Vector3d& d) {
    Eigen::Vector3d x = d;
    for (const LookupStep& step : steps) {
        x = step.a * x + step.b;
        if (step.normalize) x = safe_normalize(x);
    }
    return safe_normalize(x);
}

Eigen::Vector3f texture_lookup(const Image& image, const Eigen::Vector3d& m, EnvironmentProjection projection,
                               bool closest) {
    const Eigen::Vector2d uv = texture_coordinates(m, projection);
    const int w = image.width, h = image.height;
    // Cycles works in float from here on.
    const float x = float(uv.x() * w), y = float(uv.y() * h);
    if (closest) {
        const float column = std::clamp(std::floor(x), 0.0f, float(w)), row = std::clamp(std::floor(y), 0.0f, float(h));
        return pixel(image, long(column), long(row));
    }
    const float x0 = std::clamp(std::floor(x - 0.5f), -1.0f, float(w - 1));
    const float y0 = std::clamp(std::floor(y - 0.5f), -1.0f, float(h - 1));
    const float fx = x - 0.5f - x0, fy = y - 0.5f - y0;
    const long c = long(x0), r = long(y0);
    const Eigen::Vector3f below = (1.0f - fx) * pixel(image, c, r) + fx * pixel(image, c + 1, r);
    const Eigen::Vector3f above = (1.0f - fx) * pixel(image, c, r + 1) + fx * pixel(image, c + 1, r + 1);
    return (1.0f - fy) * below + fy * above;
}

Image environment_radiance(const std::vector<EnvironmentTerm>& terms, int width, int supersampling, int threads,
                           const Progress& progress) {
    if (width < 2) throw ArgumentError("the environment grid needs a width of at least 2, got " + std::to_string(width));
    if (supersampling < 1)
        throw ArgumentError("supersampling must be at least 1, got " + std::to_string(supersampling));
    for (const EnvironmentTerm& term : terms) check_term(term);
    Image out(width, width / 2, 3);
    ParallelOptions options;
    options.threads = threads;
    options.block = 4;
    options.stage = "image.environment_radiance";
    parallel_for(std::size_t(out.height), options, [&](std::size_t begin, std::size_t end) {
        for (std::size_t row = begin; row < end && !parallel_stop_requested(); ++row)
            radiance_row(terms, int(row), width, supersampling, out);
    }, progress);
    return out;
}

}  // namespace penumbra
