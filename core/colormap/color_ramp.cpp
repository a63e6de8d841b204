#include "colormap/color_ramp.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.hpp"

namespace penumbra::colormap {

namespace {

// Blender's BLI_math_color conversions, in float (rgb_to_hsv, hsv_to_rgb,
// rgb_to_hsl, hsl_to_rgb).
void rgb_to_hsv(const float* rgb, float* hsv) {
    float r = rgb[0], g = rgb[1], b = rgb[2];
    float k = 0.0f;
    if (g < b) {
        std::swap(g, b);
        k = -1.0f;
    }
    float min_gb = b;
    if (r < g) {
        std::swap(r, g);
        k = -2.0f / 6.0f - k;
        min_gb = std::min(g, b);
    }
    const float chroma = r - min_gb;
    hsv[0] = std::fabs(k + (g - b) / (6.0f * chroma + 1e-20f));
    hsv[1] = chroma / (r + 1e-20f);
    hsv[2] = r;
}

void hue_to_weights(float h, float& nr, float& ng, float& nb) {
    nr = std::clamp(std::fabs(h * 6.0f - 3.0f) - 1.0f, 0.0f, 1.0f);
    ng = std::clamp(2.0f - std::fabs(h * 6.0f - 2.0f), 0.0f, 1.0f);
    nb = std::clamp(2.0f - std::fabs(h * 6.0f - 4.0f), 0.0f, 1.0f);
}

void hsv_to_rgb(const float* hsv, float* rgb) {
    float nr, ng, nb;
    hue_to_weights(hsv[0], nr, ng, nb);
    const float s = hsv[1], v = hsv[2];
    rgb[0] = ((nr - 1.0f) * s + 1.0f) * v;
    rgb[1] = ((ng - 1.0f) * s + 1.0f) * v;
    rgb[2] = ((nb - 1.0f) * s + 1.0f) * v;
}

void rgb_to_hsl(const float* rgb, float* hsl) {
    const float r = rgb[0], g = rgb[1], b = rgb[2];
    const float cmax = std::max(std::max(r, g), b);
    const float cmin = std::min(std::min(r, g), b);
    float h, s;
    const float l = std::min(1.0f, (cmax + cmin) / 2.0f);
    if (cmax == cmin) {
        h = s = 0.0f;
    } else {
        const float d = cmax - cmin;
        s = l > 0.5f ? d / (2.0f - cmax - cmin) : d / (cmax + cmin);
        if (cmax == r)
            h = (g - b) / d + (g < b ? 6.0f : 0.0f);
        else if (cmax == g)
            h = (b - r) / d + 2.0f;
        else
            h = (r - g) / d + 4.0f;
    }
    hsl[0] = h / 6.0f;
    hsl[1] = s;
    hsl[2] = l;
}

void hsl_to_rgb(const float* hsl, float* rgb) {
    float nr, ng, nb;
    hue_to_weights(hsl[0], nr, ng, nb);
    const float l = hsl[2];
    const float chroma = (1.0f - std::fabs(2.0f * l - 1.0f)) * hsl[1];
    rgb[0] = (nr - 0.5f) * chroma + l;
    rgb[1] = (ng - 0.5f) * chroma + l;
    rgb[2] = (nb - 0.5f) * chroma + l;
}

// colorband_hue_interp: hue blended along the chosen way round the circle.
float hue_interp(RampHueInterpolation mode_kind, float mfac, float fac, float h1, float h2) {
    auto wrap = [](float h) { return h < 1.0f ? h : h - 1.0f; };
    h1 = wrap(h1);
    h2 = wrap(h2);
    int mode = 0;
    switch (mode_kind) {
        case RampHueInterpolation::near:
            if (h1 < h2 && (h2 - h1) > +0.5f) mode = 1;
            else if (h1 > h2 && (h2 - h1) < -0.5f) mode = 2;
            break;
        case RampHueInterpolation::far:
            if (h1 == h2) mode = 1;
            else if (h1 < h2 && (h2 - h1) < +0.5f) mode = 1;
            else if (h1 > h2 && (h2 - h1) > -0.5f) mode = 2;
            break;
        case RampHueInterpolation::ccw:
            if (h1 > h2) mode = 2;
            break;
        case RampHueInterpolation::cw:
            if (h1 < h2) mode = 1;
            break;
    }
    switch (mode) {
        case 1: return wrap(mfac * (h1 + 1.0f) + fac * h2);
        case 2: return wrap(mfac * h1 + fac * (h2 + 1.0f));
        default: return mfac * h1 + fac * h2;
    }
}

// key_curve_position_weights (blenkernel/intern/key.cc) for the two cubic kinds.
void cubic_weights(float t, float w[4], bool cardinal) {
    const float t2 = t * t, t3 = t2 * t;
    if (cardinal) {
        const float fc = 0.71f;
        w[0] = -fc * t3 + 2.0f * fc * t2 - fc * t;
        w[1] = (2.0f - fc) * t3 + (fc - 3.0f) * t2 + 1.0f;
        w[2] = (fc - 2.0f) * t3 + (3.0f - 2.0f * fc) * t2 + fc * t;
        w[3] = fc * t3 - fc * t2;
    } else {
        w[0] = -0.16666666f * t3 + 0.5f * t2 - 0.5f * t + 0.16666666f;
        w[1] = 0.5f * t3 - t2 + 0.66666666f;
        w[2] = -0.5f * t3 + 0.5f * t2 + 0.5f * t + 0.16666666f;
        w[3] = 0.16666666f * t3;
    }
}

std::vector<RampStop> sorted_stops(const ColorRamp& ramp) {
    std::vector<RampStop> stops = ramp.stops;
    // Blender sorts with qsort on position; stable_sort keeps equal positions
    // in their given order (the order Blender's RNA shows them).
    std::stable_sort(stops.begin(), stops.end(),
                     [](const RampStop& a, const RampStop& b) { return a.position < b.position; });
    return stops;
}

std::array<float, 4> evaluate_sorted(const ColorRamp& ramp, const std::vector<RampStop>& stops, float in) {
    std::array<float, 4> out{};
    const int tot = static_cast<int>(stops.size());
    // HSV/HSL modes always blend linearly (ease and the cubics are RGB only).
    const RampInterpolation ipo = ramp.color_mode == RampColorMode::rgb ? ramp.interpolation : RampInterpolation::linear;
    const bool holds_ends = ipo == RampInterpolation::linear || ipo == RampInterpolation::ease ||
                            ipo == RampInterpolation::constant;
    if (tot == 1 || (in <= stops[0].position && holds_ends))
        return stops[0].color;

    int a = 0;
    while (a < tot && !(stops[a].position > in))
        ++a;
    // cbd1: right stop, cbd2: left stop (Blender's names), padded at the ends.
    RampStop right, left;
    const RampStop *cbd1, *cbd2;
    if (a == tot) {
        cbd2 = &stops[tot - 1];
        right = *cbd2;
        right.position = 1.0f;
        cbd1 = &right;
    } else if (a == 0) {
        cbd1 = &stops[0];
        left = *cbd1;
        left.position = 0.0f;
        cbd2 = &left;
    } else {
        cbd1 = &stops[a];
        cbd2 = &stops[a - 1];
    }
    if ((a == tot && holds_ends) || ipo == RampInterpolation::constant)
        return cbd2->color;

    float fac;
    if (cbd2->position != cbd1->position)
        fac = (in - cbd1->position) / (cbd2->position - cbd1->position);
    else
        fac = a != tot ? 0.0f : 1.0f;

    if (ipo == RampInterpolation::b_spline || ipo == RampInterpolation::cardinal) {
        // Stops from right to left: 3 2 1 0 (cbd0 right of cbd1, cbd3 left of cbd2).
        const RampStop* cbd0 = a >= tot - 1 ? cbd1 : &stops[a + 1];
        const RampStop* cbd3 = a < 2 ? cbd2 : &stops[a - 2];
        fac = std::clamp(fac, 0.0f, 1.0f);
        float t[4];
        cubic_weights(fac, t, ipo == RampInterpolation::cardinal);
        for (int c = 0; c < 4; ++c)
            out[c] = std::clamp(t[3] * cbd3->color[c] + t[2] * cbd2->color[c] + t[1] * cbd1->color[c] +
                                    t[0] * cbd0->color[c],
                                0.0f, 1.0f);
        return out;
    }
    if (ipo == RampInterpolation::ease) {
        const float fac2 = fac * fac;
        fac = 3.0f * fac2 - 2.0f * fac2 * fac;
    }
    const float mfac = 1.0f - fac;
    if (ramp.color_mode == RampColorMode::rgb) {
        for (int c = 0; c < 4; ++c)
            out[c] = mfac * cbd1->color[c] + fac * cbd2->color[c];
        return out;
    }
    const bool hsv = ramp.color_mode == RampColorMode::hsv;
    float col1[3], col2[3], mixed[3];
    (hsv ? rgb_to_hsv : rgb_to_hsl)(cbd1->color.data(), col1);
    (hsv ? rgb_to_hsv : rgb_to_hsl)(cbd2->color.data(), col2);
    mixed[0] = hue_interp(ramp.hue_interpolation, mfac, fac, col1[0], col2[0]);
    mixed[1] = mfac * col1[1] + fac * col2[1];
    mixed[2] = mfac * col1[2] + fac * col2[2];
    out[3] = mfac * cbd1->color[3] + fac * cbd2->color[3];
    (hsv ? hsv_to_rgb : hsl_to_rgb)(mixed, out.data());
    return out;
}

}  // namespace

void validate_ramp(const ColorRamp& ramp) {
    if (ramp.stops.empty())
        throw ArgumentError("the ColorRamp has no colour stops");
    if (ramp.stops.size() > 32)
        throw ArgumentError("a ColorRamp has at most 32 stops, not " + std::to_string(ramp.stops.size()));
    for (std::size_t i = 0; i < ramp.stops.size(); ++i) {
        const RampStop& s = ramp.stops[i];
        if (!std::isfinite(s.position) || s.position < 0.0f || s.position > 1.0f)
            throw ArgumentError("ColorRamp stop " + std::to_string(i) + " has a position outside [0, 1]");
        for (int c = 0; c < 4; ++c)
            if (!std::isfinite(s.color[c]))
                throw ArgumentError("ColorRamp stop " + std::to_string(i) +
                                    " has a colour that is not a finite number (NaN or Inf)");
    }
}

std::array<float, 4> evaluate_ramp(const ColorRamp& ramp, float position) {
    validate_ramp(ramp);
    return evaluate_sorted(ramp, sorted_stops(ramp), position);
}

ColorMap ramp_to_color_map(const ColorRamp& ramp, RampSampling sampling, int channels, int dense_samples,
                           int table_size) {
    validate_ramp(ramp);
    if (channels != 3 && channels != 4)
        throw ArgumentError("a ramp's colour map has 3 (RGB) or 4 (RGBA) channels");
    if (dense_samples < 2)
        throw ArgumentError("dense_samples must be at least 2");
    if (table_size < 2)
        throw ArgumentError("a renderer's ramp table has at least 2 entries (Blender uses 256 or 257)");
    const std::vector<RampStop> stops = sorted_stops(ramp);
    std::vector<double> positions, colors;
    auto push = [&](double x, const std::array<float, 4>& c) {
        for (int k = 0; k < channels; ++k)
            if (!std::isfinite(c[k]))
                // Blender's HSV/HSL blends divide by zero for colours outside
                // [0, 1] (rgb_to_hsl with a negative or over-bright channel);
                // BKE_colorband_evaluate gives the same NaN, so say why.
                throw ArgumentError("the ColorRamp evaluates to NaN or Inf at position " + std::to_string(x) +
                                    (ramp.color_mode == RampColorMode::rgb
                                         ? std::string(" (colours too large for float arithmetic)")
                                         : std::string(": its HSV/HSL blend needs colours within [0, 1]; "
                                                       "use the RGB colour mode or keep the stops' colours in [0, 1]")));
        positions.push_back(x);
        colors.insert(colors.end(), c.begin(), c.begin() + channels);
    };

    if (sampling == RampSampling::cycles_table) {
        const int n = table_size;
        for (int i = 0; i < n; ++i) {
            const float x = static_cast<float>(i) / static_cast<float>(n - 1);
            push(static_cast<double>(i) / (n - 1), evaluate_sorted(ramp, stops, x));
        }
        return color_map_from_knots(std::move(positions), std::move(colors), channels,
                                    ramp.interpolation == RampInterpolation::constant ? MapInterpolation::constant
                                                                                      : MapInterpolation::linear);
    }

    const bool rgb = ramp.color_mode == RampColorMode::rgb;
    if (rgb && ramp.interpolation == RampInterpolation::constant) {
        // Step function: the colour of stop k holds from its position to the next.
        // Left of the first stop the first colour is held, which the clamped
        // extension of a knot at 0 gives.
        if (stops.front().position > 0.0f)
            push(0.0, stops.front().color);
        for (const RampStop& s : stops)
            push(s.position, s.color);
        return color_map_from_knots(std::move(positions), std::move(colors), channels, MapInterpolation::constant);
    }
    if (rgb && ramp.interpolation == RampInterpolation::linear) {
        // Piecewise linear through the stops, held beyond the end stops. Equal
        // positions make a jump: a knot pair at the same place.
        for (const RampStop& s : stops)
            push(s.position, s.color);
        return color_map_from_knots(std::move(positions), std::move(colors), channels, MapInterpolation::linear);
    }
    for (int i = 0; i < dense_samples; ++i) {
        const double x = static_cast<double>(i) / (dense_samples - 1);
        push(x, evaluate_sorted(ramp, stops, static_cast<float>(x)));
    }
    return color_map_from_knots(std::move(positions), std::move(colors), channels, MapInterpolation::linear);
}

double ramp_sampling_error(const ColorRamp& ramp, const ColorMap& map, int probes) {
    validate_ramp(ramp);
    const std::vector<RampStop> stops = sorted_stops(ramp);
    double worst = 0.0;
    double value[4];
    for (int i = 0; i < probes; ++i) {
        const double x = static_cast<double>(i) / (probes - 1);
        const std::array<float, 4> ref = evaluate_sorted(ramp, stops, static_cast<float>(x));
        map.evaluate(x, value);
        for (int c = 0; c < map.channels; ++c)
            worst = std::max(worst, std::fabs(value[c] - ref[c]));
    }
    return worst;
}

}  // namespace penumbra::colormap
