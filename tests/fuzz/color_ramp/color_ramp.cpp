// Fuzz harness: Blender ColorRamps as the add-on hands them over (stops of
// position + RGBA read from a .blend, Blender's mode names), through
// core/colormap/color_ramp.cpp (validate_ramp, evaluate_ramp,
// ramp_to_color_map, ramp_sampling_error) and on into the lookup table
// (core/colormap/lookup.cpp), as bake_colormap_lut does.
//
// Input: byte 0 interpolation, 1 colour mode, 2 hue interpolation, 3
// sampling + channels, 4 stop count (0..34), u16 dense samples; then per
// stop 5 floats (position, r, g, b, a) taken bit for bit (NaN, Inf,
// subnormal, out of range), 8 positions to evaluate, then a lookup spec and
// probes (colormap_common.hpp).
// Checked: only penumbra::Error; an accepted ramp evaluates to finite values
// where its colours are ordinary (see `ordinary`); lookups stay within the
// map's range.
#include "../colormap_common.hpp"
#include "colormap/color_ramp.hpp"

using namespace penumbra;
using namespace penumbra::colormap;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fuzz::Bytes in(data, size);
    ColorRamp ramp;
    ramp.interpolation = RampInterpolation(in.byte() % 5);
    ramp.color_mode = RampColorMode(in.byte() % 3);
    ramp.hue_interpolation = RampHueInterpolation(in.byte() % 4);
    const std::uint8_t flags = in.byte();
    const RampSampling sampling = flags & 1 ? RampSampling::exact : RampSampling::cycles_table;
    const int channels = flags & 2 ? 4 : 3;
    const int stops = in.byte() % 35;
    const int dense_samples = in.in_range(0, 2048);
    // Colours for which evaluation must stay finite: RGB within ±1e6; HSV and
    // HSL within [0, 1], because outside it Blender's rgb_to_hsl divides by
    // zero (BKE_colorband_evaluate gives NaN there too; the colour map then
    // refuses the ramp with an ArgumentError saying so).
    const bool rgb = ramp.color_mode == RampColorMode::rgb;
    bool ordinary = true;
    for (int i = 0; i < stops; ++i) {
        RampStop s;
        s.position = in.take<float>();
        for (auto& c : s.color) {
            c = in.take<float>();
            ordinary = ordinary && (rgb ? std::fabs(c) <= 1e6f : c >= 0.0f && c <= 1.0f);
        }
        ramp.stops.push_back(s);
    }
    float positions[8];
    for (auto& p : positions) p = in.take<float>();

    fuzz::expect_only_penumbra_errors([&] {
        validate_ramp(ramp);
        for (float p : positions) {
            const auto rgba = evaluate_ramp(ramp, p);
            if (ordinary && std::isfinite(p))
                for (float v : rgba)
                    penumbra_fuzz_check(std::isfinite(v), "an accepted ramp evaluated to NaN or Inf");
        }
        const ColorMap map = ramp_to_color_map(ramp, sampling, channels, dense_samples);
        penumbra_fuzz_check(map.channels == channels && map.knot_count() >= 1, "a ramp gave an empty colour map");
        const double error = ramp_sampling_error(ramp, map, 101);
        if (ordinary) penumbra_fuzz_check(std::isfinite(error), "the ramp's sampling error is not finite");
        const LookupSpec spec = fuzz::take_spec(in);
        spec.validate();
        fuzz::check_lookup(map, spec, in);
    });
    return 0;
}
