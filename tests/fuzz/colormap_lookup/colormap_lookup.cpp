// Fuzz harness: colour maps that come from a lookup image (the add-on's
// "bake from image": the image's middle row of colour samples,
// color_map_from_samples) or from knots (color_map_from_knots), the lookup
// table built from them (core/colormap/lookup.cpp), and look-ups in a table
// image handed in from outside (colormap_lut_accuracy's `table`).
//
// Input: byte 0 picks samples or knots (bit 0) and constant or linear
// knots (bit 1); byte 1 channels (1..4 accepted, 0..5 tried); u16 count
// (0..70); then the values (float samples; double positions and colours
// for knots) bit for bit; a lookup spec and probes (colormap_common.hpp);
// then a table image: width and height (1..8), channels, float texels.
// Checked: only penumbra::Error; filtered colours and texels stay within the
// map's range; a bilinear look-up stays within the table's range.
#include "../colormap_common.hpp"

using namespace penumbra;
using namespace penumbra::colormap;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fuzz::Bytes in(data, size);
    const std::uint8_t mode = in.byte();
    const int channels = in.byte() % 6;
    const int count = in.in_range(0, 70);
    fuzz::expect_only_penumbra_errors([&] {
        ColorMap map;
        if (mode & 1) {
            std::vector<double> positions(count), colors(std::size_t(count) * std::max(channels, 0));
            for (auto& p : positions) p = in.take<double>();
            for (auto& c : colors) c = in.take<double>();
            map = color_map_from_knots(std::move(positions), std::move(colors), channels,
                                       mode & 2 ? MapInterpolation::constant : MapInterpolation::linear);
        } else {
            std::vector<float> samples(std::size_t(count) * std::max(channels, 1));
            for (auto& s : samples) s = in.take<float>();
            map = color_map_from_samples(samples.data(), count, channels);
        }
        const LookupSpec spec = fuzz::take_spec(in);
        spec.validate();
        fuzz::check_lookup(map, spec, in);
    });

    // A table image from outside, with a spec of its size (as the binding makes it).
    Image table(in.in_range(1, 8), in.in_range(1, 8), in.in_range(1, 4));
    for (auto& v : table.pixels) v = in.take<float>();
    LookupSpec spec;
    spec.width = table.width;
    spec.height = table.height;
    spec.sigma_max = in.take<double>();
    spec.mean_min = in.take<double>();
    spec.mean_max = in.take<double>();
    fuzz::expect_only_penumbra_errors([&] {
        spec.validate();
        float lo = INFINITY, hi = -INFINITY;
        bool finite = true;
        for (float v : table.pixels) {
            lo = std::min(lo, v);
            hi = std::max(hi, v);
            finite = finite && std::isfinite(v);
        }
        std::vector<double> out(table.channels);
        for (int probe = 0; probe < 4; ++probe) {
            const double mean = in.take<double>(), sigma = in.take<double>();
            bilinear_lookup(table, spec, mean, sigma, out.data());
            if (!finite) continue;
            for (double v : out)
                penumbra_fuzz_check(v >= lo - 1e-6 * std::fabs(lo) && v <= hi + 1e-6 * std::fabs(hi),
                                    "a bilinear look-up lies outside the table's range");
        }
    });
    return 0;
}
