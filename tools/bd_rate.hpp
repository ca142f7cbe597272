#pragma once
// Bjøntegaard delta rate: the mean bit-rate difference of a test codec against an anchor at equal
// quality, over the quality interval both curves cover. log10(rate) is interpolated as a function
// of quality by piecewise cubic Hermite interpolation with monotone (Fritsch-Carlson) slopes, as
// in the common VCEG/JVET practice, and integrated exactly.
#include <vector>

namespace reprise::cli {

struct RatePoint {
    double rate = 0.0;     // bits (per frame, per second or in all: the same unit on both sides)
    double quality = 0.0;  // higher is better (pass -FLIP for FLIP)
};

// Percent: -20 means the test needs 20 % fewer bits for the same quality. NaN when either curve
// has fewer than two points with distinct finite quality and positive rate, or when the quality
// intervals do not overlap.
double bd_rate(std::vector<RatePoint> anchor, std::vector<RatePoint> test);

// The integral of the interpolated log10(rate) over [lo, hi] (inside the curve's range): exposed
// for the test.
double integrate_log_rate(std::vector<RatePoint> curve, double lo, double hi);

}  // namespace reprise::cli
