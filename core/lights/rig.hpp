// The light-rig pipeline over time: frames in (an image, a sequence, a
// video), per-frame lights, temporal filtering by light index, optional
// clustering, rotation into Blender world coordinates.
//
//   per frame:  radiance → EnvironmentMap → luminance PDF → sampler → lights
//               (fixed count, or adaptive up to the count as a budget:
//               one count per shot, the largest any of its frames needs)
//               (or carried over from the previous frame: tracking.hpp)
//   finish():   FIR filter per light index within each shot (temporal.hpp)
//               → clustering per frame (clustering.hpp) → world_from_map ·
//               direction
//
// Every frame of the result has `slots` lights, slot k = light index k (a
// Blender sun per slot): a light absent in a frame (above that frame's
// adaptive count, or merged into a cluster seeded by a lower index) has
// power 0 there and keeps a sensible direction, so a keyframed rig never
// jumps. Per-frame defect counts (NaN, Inf, negative pixels) are kept.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "color/color_config.hpp"
#include "common/progress.hpp"
#include "common/setting.hpp"
#include "image/frame_source.hpp"
#include "lights/clustering.hpp"
#include "lights/environment.hpp"
#include "lights/frame_lights.hpp"
#include "lights/map_reader.hpp"
#include "lights/motion.hpp"
#include "lights/temporal.hpp"
#include "lights/tracking.hpp"

namespace penumbra::lights {

struct RigOptions {
    MapOptions map;
    LightOptions lights;            // lights.count is the count, or the budget when adaptive
    // How lights carry over from frame to frame (tracking.hpp). FOLLOW needs
    // region powers; equal powers always resample.
    Tracking tracking = Tracking::follow;
    TrackingOptions track;
    bool temporal_filter = true;
    bool filter_brightness = false; // also low-pass each frame's total (the paper's; temporal.hpp)
    double frames_per_second = 0.0; // 0: the source's rate, else 21 (the paper's)
    double pass_hz = paper_pass_hz, stop_hz = paper_stop_hz;  // temporal.hpp: the paper's filter's edges
    int cluster_max = 0;            // Q; 0 = no clustering
    static constexpr Range<int> cluster_max_range{0, unbounded_int};
    double cluster_correction = 1.85;
    // > 0: per shot the fewest lights (up to lights.count, and the renderer's
    // max_lights) whose fitted suns, as lights.sun_model draws them, keep
    // every frame of the shot within this irradiance error (adaptive_count).
    // The frames of a shot wait in memory (their working maps) until the
    // next cut, so that the shot is tracked with the one count it needs.
    double adaptive_tolerance = 0.0;
    static constexpr Range<double> adaptive_tolerance_range{0.0, 1.0};
    Eigen::Matrix3d world_from_map = Eigen::Matrix3d::Identity();
};

struct RigFrame {
    std::vector<Light> lights;       // `slots` entries, world coordinates
    int active = 0;                  // lights with power > 0
    Eigen::Vector3d total_rgb = Eigen::Vector3d::Zero();
    double total_power = 0.0;
    PixelDefects defects;
    double adaptive_error = -1.0;    // the irradiance error of this frame's lights at its shot's count
                                     // (rig_error, before the temporal filter; adaptive count only)
    int adaptive_count = 0;          // the count of this frame's shot (adaptive count only)
};

struct LightRig {
    std::vector<RigFrame> frames;
    int slots = 0;
    bool full_sphere = true;
    FirFilter filter;                // empty when not filtered
    double frames_per_second = 0.0;
    double cluster_radius = 0.0;     // ε used in the last frame (0: no clustering)
    int adaptive_count = 0;          // the largest shot count (adaptive count only)
    double adaptive_error = -1.0;    // the largest frame error at its shot's count (adaptive count only)
};

class RigBuilder {
public:
    explicit RigBuilder(RigOptions options);

    // One frame of scene-linear radiance in the input projection. Validates
    // the count against the working map; ArgumentError on bad input.
    void add_frame(const Image& radiance, const Progress& progress = {});
    // One frame already made into a working map with options().map (e.g. by
    // LightSource::read_map, which streams large files).
    void add_map(EnvironmentMap map);
    int frame_count() const { return int(raw_.size() + shot_maps_.size()); }
    const EnvironmentMap& last_map() const { return last_map_; }
    const RigOptions& options() const { return options_; }

    LightRig finish(double source_frames_per_second = 0.0) const;

private:
    // The lights of one shot's frames at one count (the largest any frame
    // needs), with the cuts the tracker saw and each frame's error.
    struct Shot {
        std::vector<FrameLights> lights;
        std::vector<bool> cuts;
        std::vector<double> errors;
        int count = 0;
    };
    Shot light_shot(const std::vector<EnvironmentMap>& maps, const std::vector<int>& needs) const;
    void end_shot();
    bool starts_shot(const EnvironmentMap& map);

    RigOptions options_;
    bool following() const;
    std::vector<FrameLights> raw_;
    std::vector<bool> cuts_;         // frame t starts a shot (the filter does not blend across)
    std::optional<LightTracker> tracker_;
    std::vector<PixelDefects> defects_;
    std::vector<double> errors_;
    std::vector<int> counts_;        // the shot count per frame (adaptive only)
    // Adaptive only: the current shot's maps and the count each needs, and
    // the signature and motion that tell where the next shot starts.
    std::vector<EnvironmentMap> shot_maps_;
    std::vector<int> shot_needs_;
    MapSignature signature_;
    Eigen::Matrix3d motion_ = Eigen::Matrix3d::Identity();
    EnvironmentMap last_map_;
};

// Reads frames [start, start + count) of `source` (count < 0: to the end),
// converts each from `colorspace` to the config's scene_linear (no
// conversion when `config` is null), and builds the rig. Progress is
// reported once per frame; Cancelled leaves nothing behind.
LightRig build_light_rig(const FrameSource& source, const ColorConfig* config, const std::string& colorspace,
                         const RigOptions& options, int start = 0, int count = -1,
                         const Progress& progress = {});
// The same from a LightSource: image files and sequence frames stream
// (lights/map_reader.hpp), so a 16k map never sits in memory whole.
LightRig build_light_rig(const LightSource& source, const ColorConfig* config, const std::string& colorspace,
                         const RigOptions& options, int start = 0, int count = -1,
                         const Progress& progress = {});

// A picture of where the lights sit on the map (the paper's Figure 1): the
// working map at most `max_width` wide, exposed so its mean luminance is 0.18
// and compressed by x/(1+x) into [0, 1) (scene-linear; convert to a display
// space to view), with a green ring per light of non-zero power whose radius
// grows with √power. `lights` in world coordinates; `world_from_map` as used
// for the rig (its inverse places them on the map).
Image preview_image(const EnvironmentMap& map, const std::vector<Light>& lights,
                    const Eigen::Matrix3d& world_from_map = Eigen::Matrix3d::Identity(), int max_width = 512);

}  // namespace penumbra::lights
