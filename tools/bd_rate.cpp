#include "bd_rate.hpp"

#include <algorithm>
#include <cmath>

namespace reprise::cli {

namespace {

// Points with positive finite rate and finite quality, by increasing quality; of equal
// qualities the lowest rate stays.
std::vector<RatePoint> clean(std::vector<RatePoint> curve) {
    std::erase_if(curve, [](const RatePoint& p) {
        return !(p.rate > 0.0) || !std::isfinite(p.rate) || !std::isfinite(p.quality);
    });
    std::sort(curve.begin(), curve.end(), [](const RatePoint& a, const RatePoint& b) {
        return a.quality != b.quality ? a.quality < b.quality : a.rate < b.rate;
    });
    curve.erase(
        std::unique(curve.begin(), curve.end(),
                    [](const RatePoint& a, const RatePoint& b) { return a.quality == b.quality; }),
        curve.end());
    return curve;
}

double sign(double v) { return (v > 0.0) - (v < 0.0); }

// Monotone cubic Hermite slopes (Fritsch-Carlson with the weighted harmonic mean, as pchip).
std::vector<double> slopes(const std::vector<double>& x, const std::vector<double>& y) {
    const std::size_t n = x.size();
    std::vector<double> h(n - 1), delta(n - 1), d(n, 0.0);
    for (std::size_t k = 0; k + 1 < n; ++k) {
        h[k] = x[k + 1] - x[k];
        delta[k] = (y[k + 1] - y[k]) / h[k];
    }
    if (n == 2) {
        d[0] = d[1] = delta[0];
        return d;
    }
    for (std::size_t k = 1; k + 1 < n; ++k) {
        if (delta[k - 1] * delta[k] <= 0.0) continue;
        const double w1 = 2.0 * h[k] + h[k - 1], w2 = h[k] + 2.0 * h[k - 1];
        d[k] = (w1 + w2) / (w1 / delta[k - 1] + w2 / delta[k]);
    }
    auto end_slope = [](double h0, double h1, double d0, double d1) {
        double s = ((2.0 * h0 + h1) * d0 - h0 * d1) / (h0 + h1);
        if (sign(s) != sign(d0))
            s = 0.0;
        else if (sign(d0) != sign(d1) && std::abs(s) > std::abs(3.0 * d0))
            s = 3.0 * d0;
        return s;
    };
    d[0] = end_slope(h[0], h[1], delta[0], delta[1]);
    d[n - 1] = end_slope(h[n - 2], h[n - 3], delta[n - 2], delta[n - 3]);
    return d;
}

// The integral over t in [0, t] of the Hermite basis on the unit interval.
double int_h00(double t) { return t * t * t * t / 2.0 - t * t * t + t; }
double int_h10(double t) { return t * t * t * t / 4.0 - 2.0 * t * t * t / 3.0 + t * t / 2.0; }
double int_h01(double t) { return -t * t * t * t / 2.0 + t * t * t; }
double int_h11(double t) { return t * t * t * t / 4.0 - t * t * t / 3.0; }

}  // namespace

double integrate_log_rate(std::vector<RatePoint> curve, double lo, double hi) {
    curve = clean(std::move(curve));
    const std::size_t n = curve.size();
    if (n < 2 || !(lo <= hi)) return NAN;
    std::vector<double> x(n), y(n);
    for (std::size_t k = 0; k < n; ++k) x[k] = curve[k].quality, y[k] = std::log10(curve[k].rate);
    const std::vector<double> d = slopes(x, y);
    double sum = 0.0;
    for (std::size_t k = 0; k + 1 < n; ++k) {
        const double a = std::max(lo, x[k]), b = std::min(hi, x[k + 1]);
        if (!(a < b)) continue;
        const double h = x[k + 1] - x[k];
        auto antiderivative = [&](double t) {
            return h * (y[k] * int_h00(t) + h * d[k] * int_h10(t) + y[k + 1] * int_h01(t) +
                        h * d[k + 1] * int_h11(t));
        };
        sum += antiderivative((b - x[k]) / h) - antiderivative((a - x[k]) / h);
    }
    return sum;
}

double bd_rate(std::vector<RatePoint> anchor, std::vector<RatePoint> test) {
    anchor = clean(std::move(anchor));
    test = clean(std::move(test));
    if (anchor.size() < 2 || test.size() < 2) return NAN;
    const double lo = std::max(anchor.front().quality, test.front().quality);
    const double hi = std::min(anchor.back().quality, test.back().quality);
    if (!(lo < hi)) return NAN;
    const double mean_diff =
        (integrate_log_rate(test, lo, hi) - integrate_log_rate(anchor, lo, hi)) / (hi - lo);
    return (std::pow(10.0, mean_diff) - 1.0) * 100.0;
}

}  // namespace reprise::cli
