#include "lights/rig.hpp"

#include <algorithm>
#include <iterator>
#include <cmath>
#include <numbers>
#include <string>

#include <Eigen/LU>

#include "common/math.hpp"
#include "common/error.hpp"

namespace penumbra::lights {

RigBuilder::RigBuilder(RigOptions options) : options_(std::move(options)) {
    if (options_.lights.count < 1)
        throw ArgumentError("the light count must be at least 1, got " + std::to_string(options_.lights.count));
    check_range("cluster_max (0: off)", options_.cluster_max, RigOptions::cluster_max_range);
    check_range("the adaptive tolerance (0: off)", options_.adaptive_tolerance, RigOptions::adaptive_tolerance_range);
    const Eigen::Matrix3d& m = options_.world_from_map;
    if (!m.allFinite() || (m.transpose() * m - Eigen::Matrix3d::Identity()).norm() > 1e-6 || m.determinant() < 0)
        throw ArgumentError("world_from_map must be a rotation matrix");
}

void RigBuilder::add_frame(const Image& radiance, const Progress& progress) {
    EnvironmentMap map = make_environment(radiance, options_.map, progress);
    if (!raw_.empty() && (map.width != last_map_.width || map.height != last_map_.height))
        throw ArgumentError("frame " + std::to_string(raw_.size()) + " is " + std::to_string(radiance.width) + "x" +
                            std::to_string(radiance.height) + " but earlier frames were a different size; every "
                            "frame of a light-rig source must have the same size");
    add_map(std::move(map));
}

void RigBuilder::add_map(EnvironmentMap map) {
    if (!raw_.empty() && (map.width != last_map_.width || map.height != last_map_.height ||
                          map.full_sphere != last_map_.full_sphere))
        throw ArgumentError("frame " + std::to_string(raw_.size()) + " gives a " + std::to_string(map.width) + "x" +
                            std::to_string(map.height) + " working map but earlier frames gave " +
                            std::to_string(last_map_.width) + "x" + std::to_string(last_map_.height) +
                            "; every frame of a light-rig source must have the same size");
    const PixelDefects defects = map.defects;
    defects_.push_back(defects);
    if (options_.adaptive_tolerance > 0.0) {
        if (starts_shot(map)) end_shot();
        const AdaptiveResult a =
            adaptive_count(map, options_.lights, options_.adaptive_tolerance, options_.lights.count);
        shot_needs_.push_back(a.count);
        last_map_ = map;
        shot_maps_.push_back(std::move(map));
        return;
    }
    FrameLights lights;
    bool cut = raw_.empty();
    if (following()) {
        if (!tracker_) tracker_.emplace(options_.lights, options_.track);
        lights = tracker_->next(map, cut);
    } else {
        lights = compute_lights(map, options_.lights);
    }
    raw_.push_back(std::move(lights));
    cuts_.push_back(cut);
    errors_.push_back(-1.0);
    last_map_ = std::move(map);
}

// A new shot starts where the map's change is no rotation (the tracker's own
// test, tracking.hpp), so that a shot's count holds only over its frames.
bool RigBuilder::starts_shot(const EnvironmentMap& map) {
    MapSignature signature = map_signature(map, options_.lights.luminance, options_.lights.threads);
    bool cut = true;
    if (!shot_maps_.empty()) {
        const MapMotion m = estimate_rotation(signature_, signature, motion_);
        cut = m.residual > options_.track.cut_residual;
        motion_ = cut ? Eigen::Matrix3d::Identity() : m.rotation;
    }
    signature_ = std::move(signature);
    return cut;
}

void RigBuilder::end_shot() {
    if (shot_maps_.empty()) return;
    Shot shot = light_shot(shot_maps_, shot_needs_);
    for (std::size_t t = 0; t < shot.lights.size(); ++t) {
        raw_.push_back(std::move(shot.lights[t]));
        cuts_.push_back(shot.cuts[t]);
        errors_.push_back(shot.errors[t]);
        counts_.push_back(shot.count);
    }
    shot_maps_.clear();
    shot_needs_.clear();
}

RigBuilder::Shot RigBuilder::light_shot(const std::vector<EnvironmentMap>& maps, const std::vector<int>& needs) const {
    Shot shot;
    shot.count = *std::max_element(needs.begin(), needs.end());
    LightOptions o = options_.lights;
    o.count = shot.count;
    // Resampled frames are one shot for the temporal filter, as without the
    // adaptive count; a followed shot starts afresh at its first frame.
    std::optional<LightTracker> tracker;
    if (following()) tracker.emplace(o, options_.track);
    for (std::size_t t = 0; t < maps.size(); ++t) {
        bool cut = raw_.empty() && t == 0;
        shot.lights.push_back(tracker ? tracker->next(maps[t], cut) : compute_lights(maps[t], o));
        shot.cuts.push_back(cut);
        shot.errors.push_back(rig_error(maps[t], shot.lights.back().lights, o.sun_model, o.luminance, 128, o.threads));
    }
    return shot;
}

bool RigBuilder::following() const {
    return options_.tracking == Tracking::follow && options_.lights.power == PowerMode::region;
}

LightRig RigBuilder::finish(double source_fps) const {
    LightRig rig;
    rig.full_sphere = last_map_.full_sphere;
    rig.frames_per_second = options_.frames_per_second > 0.0 ? options_.frames_per_second
                            : source_fps > 0.0              ? source_fps
                                                            : 21.0;
    std::vector<FrameLights> frames = raw_;
    std::vector<bool> cuts = cuts_;
    std::vector<double> errors = errors_;
    std::vector<int> counts = counts_;
    if (!shot_maps_.empty()) {  // the last shot of an adaptive rig
        Shot shot = light_shot(shot_maps_, shot_needs_);
        std::move(shot.lights.begin(), shot.lights.end(), std::back_inserter(frames));
        cuts.insert(cuts.end(), shot.cuts.begin(), shot.cuts.end());
        errors.insert(errors.end(), shot.errors.begin(), shot.errors.end());
        counts.insert(counts.end(), shot.lights.size(), shot.count);
    }
    int slots = 0;
    for (const auto& f : frames) slots = std::max(slots, int(f.lights.size()));
    rig.slots = slots;

    if (options_.temporal_filter && frames.size() > 1) {
        rig.filter = filter_for_rate(rig.frames_per_second, options_.pass_hz, options_.stop_hz);
        // Shot by shot: light k of one shot has nothing to do with light k of the next.
        for (std::size_t begin = 0; begin < frames.size();) {
            std::size_t end = begin + 1;
            while (end < frames.size() && !cuts[end]) ++end;
            std::vector<FrameLights> shot(frames.begin() + long(begin), frames.begin() + long(end));
            filter_lights(shot, rig.filter, options_.filter_brightness);  // absent lights count as power 0
            std::move(shot.begin(), shot.end(), frames.begin() + long(begin));
            begin = end;
        }
    }
    // Pad every frame to `slots` with power-0 lights that keep the direction
    // of the nearest frame where they exist, so a keyframed sun never jumps.
    const int n = int(frames.size());
    for (int t = 0; t < n; ++t)
        for (int k = int(frames[t].lights.size()); k < slots; ++k) {
            Light l;
            l.index = k;
            for (int step = 1; step < n; ++step) {
                const int before = t - step, after = t + step;
                if (before >= 0 && int(frames[before].lights.size()) > k) { l.direction = frames[before].lights[k].direction; break; }
                if (after < n && int(frames[after].lights.size()) > k) { l.direction = frames[after].lights[k].direction; break; }
            }
            l.sample_direction = l.direction;
            frames[t].lights.push_back(l);
        }

    rig.frames.resize(frames.size());
    for (std::size_t t = 0; t < frames.size(); ++t) {
        RigFrame& out = rig.frames[t];
        out.defects = defects_[t];
        out.adaptive_error = errors[t];
        if (!counts.empty()) {
            out.adaptive_count = counts[t];
            rig.adaptive_count = std::max(rig.adaptive_count, counts[t]);
            rig.adaptive_error = std::max(rig.adaptive_error, errors[t]);
        }
        std::vector<Light> lights = frames[t].lights;
        if (options_.cluster_max > 0) {
            ClusterOptions co;
            co.max_clusters = options_.cluster_max;
            co.correction = options_.cluster_correction;
            co.full_sphere = rig.full_sphere;
            const Clustering c = cluster_lights(lights, co);
            rig.cluster_radius = c.radius;
            for (auto& l : lights) {
                l.rgb.setZero();
                l.power = 0.0;
            }
            for (const Light& cl : c.clusters) lights[cl.index] = cl;
        }
        for (auto& l : lights) {
            l.direction = (options_.world_from_map * l.direction).normalized();
            l.sample_direction = (options_.world_from_map * l.sample_direction).normalized();
            out.total_rgb += l.rgb;
            out.total_power += l.power;
            if (l.power > 0.0) ++out.active;
        }
        out.lights = std::move(lights);
    }
    return rig;
}

LightRig build_light_rig(const FrameSource& source, const ColorConfig* config, const std::string& colorspace,
                         const RigOptions& options, int start, int count, const Progress& progress) {
    const int total = source.frame_count();
    if (start < 0 || start >= total)
        throw ArgumentError("start frame " + std::to_string(start) + " is outside 0.." + std::to_string(total - 1) +
                            " of " + source.describe());
    const int end = count < 0 ? total : std::min(total, start + count);
    RigBuilder builder(options);
    for (int i = start; i < end; ++i) {
        progress.report(double(i - start) / std::max(1, end - start));
        Image frame = source.read(i);
        if (config) config->to_scene_linear(frame, colorspace);
        builder.add_frame(frame);
    }
    progress.report(1.0);
    return builder.finish(source.frames_per_second());
}

LightRig build_light_rig(const LightSource& source, const ColorConfig* config, const std::string& colorspace,
                         const RigOptions& options, int start, int count, const Progress& progress) {
    const FrameSource& frames = source.frames();
    const int total = frames.frame_count();
    if (start < 0 || start >= total)
        throw ArgumentError("start frame " + std::to_string(start) + " is outside 0.." + std::to_string(total - 1) +
                            " of " + frames.describe());
    const int end = count < 0 ? total : std::min(total, start + count);
    RigBuilder builder(options);
    for (int i = start; i < end; ++i) {
        progress.report(double(i - start) / std::max(1, end - start));
        builder.add_map(source.read_map(i, config, colorspace, options.map));
    }
    progress.report(1.0);
    return builder.finish(frames.frames_per_second());
}

Image preview_image(const EnvironmentMap& map, const std::vector<Light>& lights, const Eigen::Matrix3d& world_from_map,
                    int max_width) {
    if (map.width < 1 || map.height < 1) throw ArgumentError("cannot preview an empty map");
    if (max_width < 8) throw ArgumentError("the preview must be at least 8 pixels wide");
    // Reduce (energy-exact) and expose.
    MapOptions reduce;
    reduce.projection = map.full_sphere ? Projection::equirectangular : Projection::hemisphere_polar;
    reduce.max_width = max_width;
    Image copy(map.width, map.height, 3);
    copy.pixels = map.rgb;
    const EnvironmentMap small = make_environment(copy, reduce);
    Image out(small.width, small.height, 3);
    double mean = 0.0;
    for (std::size_t i = 0; i < small.rgb.size() / 3; ++i)
        mean += rec709_luminance[0] * small.rgb[3 * i] + rec709_luminance[1] * small.rgb[3 * i + 1] +
                rec709_luminance[2] * small.rgb[3 * i + 2];
    mean /= double(small.rgb.size() / 3);
    const double exposure = mean > 0.0 ? 0.18 / mean : 1.0;
    for (std::size_t i = 0; i < small.rgb.size(); ++i) {
        const double v = exposure * small.rgb[i];
        out.pixels[i] = float(v / (1.0 + v));
    }
    double max_power = 0.0;
    for (const auto& l : lights) max_power = std::max(max_power, l.power);
    const Eigen::Matrix3d map_from_world = world_from_map.transpose();
    const Projection projection = small.full_sphere ? Projection::equirectangular : Projection::hemisphere_polar;
    for (const auto& l : lights) {
        if (!(l.power > 0.0)) continue;
        double x, y;
        if (!direction_to_image(projection, {}, out.width, out.height, map_from_world * l.direction, x, y)) continue;
        const double radius = 1.5 + 0.012 * out.width * std::sqrt(l.power / max_power);
        const int r = int(std::ceil(radius + 1));
        for (int dy = -r; dy <= r; ++dy)
            for (int dx = -r; dx <= r; ++dx) {
                const double dist = length_2d(dx, dy);
                if (std::abs(dist - radius) > 0.75) continue;
                const int px = ((int(std::floor(x)) + dx) % out.width + out.width) % out.width;
                const int py = int(std::floor(y)) + dy;
                if (py < 0 || py >= out.height) continue;
                out.at(px, py, 0) = 0.0f;
                out.at(px, py, 1) = 1.0f;
                out.at(px, py, 2) = 0.0f;
            }
    }
    return out;
}

}  // namespace penumbra::lights
