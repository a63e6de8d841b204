// Temporal filtering of tracked lights (paper §3.3): a linear-phase FIR
// low-pass applied per light index to the direction (the 3D vector,
// renormalized afterwards) and to the power.
//
// Default: the paper's 9-tap equiripple filter for 21 Hz capture (stated as
// pass 7 Hz, stop 9 Hz): w = 0.06216, 0.01296, −0.13816, 0.28315, 0.65223,
// (mirrored). Its response is equiripple (δ ≈ 0.092 in both bands) but with
// band edges near 5.9 Hz and 8.05 Hz: our Remez design for those edges
// reproduces the printed taps to 0.0013 (tested), while 7/9 Hz gives a
// different filter. So the default edges for other frame rates are 5.9 Hz and
// 8.05 Hz: the same frequency response as the paper's filter.
// The printed taps sum to 1.09245; they are divided by that sum so a constant
// signal passes unchanged (the paper: "the overall energy in the system is
// preserved, which is naturally achieved through normalizing the filter
// weighting coefficients").
// Other frame rates: an equiripple (Parks–McClellan / Remez exchange) design
// from pass and stop frequencies, with as many taps as Kaiser's estimate asks
// for the paper's ripple (δ ≈ 0.09), then normalized to unit DC gain. A stop
// edge at or above the Nyquist frequency scales both edges with the rate
// (5.9/21 and 8.05/21 of it).
//
// Delay and ends. Streaming (as in the paper's live system) a causal
// (2D+1)-tap filter delays the lights by D frames (4 for the paper's). A
// light rig is built offline from the whole video, so filter_sequence applies
// the same taps centred on each frame: zero delay, and, the taps being
// symmetric, zero phase. Within D frames of the first or last frame (of a
// shot: the rig filters each shot apart, rig.hpp) the window shrinks to the
// widest centred one that fits, renormalized (down to the frame alone at the
// ends): still symmetric, so a light moving steadily stays where it is (a
// window padded with copies of the end frame would pull it back by a
// fraction of its motion, which for a sun turning 1° per frame cost up to
// 2.1× median cut's irradiance error; measured in lights-benchmark.md), at
// the price of less smoothing near the ends.
//
// Energy. The taps sum to 1; every light's RGB power is filtered with the
// same taps, so by linearity the lights' sum is the filtered sum. Negative
// taps can push a light that switches on to slightly negative power: such
// values are set to 0. Then each frame's lights are rescaled to a total: by
// default the frame's own (the unfiltered lights' sum), so the filter moves
// power between lights but never changes how bright a frame is — a rig then
// follows exposure changes and flicker of the source as they are, frame by
// frame (issue #14 goal 2: each frame as accurate as that frame allows);
// with `filter_brightness` the filtered sum, the paper's: the total is low-
// passed too, which removes a lamp's aliased flicker but also the frame's
// own brightness. Directions are filtered as vectors and renormalized (a
// vector that cancels to near zero keeps the frame's own direction), which
// changes no power.
#pragma once

#include <vector>

#include "lights/frame_lights.hpp"

namespace penumbra::lights {

struct FirFilter {
    std::vector<double> taps;  // odd length, symmetric, Σ = 1
    int delay() const { return int(taps.size() / 2); }  // frames, when used causally
    // |H(f)| at frequency f (Hz) for sampling rate `rate` (Hz).
    double gain(double frequency, double rate) const;
    // The taps used at frame t of n (see "Delay and ends" above).
    std::vector<double> window(int t, int n) const;
};

// The paper's filter, normalized.
FirFilter paper_filter();

// Equiripple linear-phase low-pass (Parks–McClellan, equal weights in both
// bands). taps = 0: Kaiser's estimate for ripple 0.06, odd, in [3, 255].
// ArgumentError unless 0 < pass < stop and rate > 0.
FirFilter design_lowpass(double rate_hz, double pass_hz, double stop_hz, int taps = 0);

// The filter the tool uses at `rate_hz`: the paper's at 21 Hz (±0.5 Hz) with
// the paper's edges, else design_lowpass (edges scaled as described above).
// The paper's capture rate and the band edges that reproduce its filter.
inline constexpr double paper_rate_hz = 21.0, paper_pass_hz = 5.9, paper_stop_hz = 8.05;

FirFilter filter_for_rate(double rate_hz, double pass_hz = paper_pass_hz, double stop_hz = paper_stop_hz);

// Centred filtering with edge replication (see above).
std::vector<double> filter_sequence(const std::vector<double>& signal, const FirFilter& filter);

// Filters frames[t].lights[k] across t for each light index k: direction
// vectors (renormalized), RGB power, spread; then rescales each frame's
// lights to its own total (filter_brightness: to the filtered total). Lights
// are matched by `index`; a light missing from a frame (adaptive count)
// counts as power 0 there, with the direction of its nearest frame's. The
// frames' total_rgb and total_power become their lights' sums.
void filter_lights(std::vector<FrameLights>& frames, const FirFilter& filter, bool filter_brightness = false);

}  // namespace penumbra::lights
