// `--warp auto --fill auto`: error and cost models per candidate setting, in the manner of
// Sitthi-amorn et al. 2008 (error saturating exponentially with how far a value is reused, cost
// linear in the work), evaluated at run time on predictors surveyed before warping.
#include <algorithm>
#include <cmath>

#include "reprise/warp/fruc.hpp"

namespace reprise::warp {

namespace {

constexpr int kStep = 8;  // the survey: every 8th pixel of every 8th row

// The reference setting (grid+pullpush) has Sitthi-amorn's saturating error: mean squared error
// of display values at warp distance t (input periods)
//   floor + alpha (1 - exp(-lambda v)) + beta sigma + kappa d,
// v = motion t, sigma = spread t, d = disoccluded t (FramePredictors). Every candidate's PSNR
// differs from the reference's by delta . (1, v, sigma, d); a candidate without fill also leaves
// its holes black, about 0.25 d of squared error more. Costs in ns per pixel: [warp][fill], the
// warp alone under fill none. Fitted by scripts/fit_auto.py to a `reprise bench fruc` run
// (640x360, x2, 19 frames each of pan, fence, crossing, specular, fast, courtyard, stroll; session
// 38, after one-warp extrapolation, the bicubic grid, refinement and blending on the display's
// scale; its data in docs/results/auto-fit/, the fit's errors in docs/benchmarks.md).
struct ErrorModel {
    float floor, alpha, lambda, beta, kappa;
};
struct Model {
    ErrorModel reference;
    float delta[kAutoCandidates][4];
    float cost[3][3];
};

// [mode] interpolate, extrapolate
constexpr Model kModels[2] = {
    // interpolate
    {{1.000e-06f, 0.000e+00f, 0.010f, 0.000e+00f, 5.123e-03f},
     {{-0.9917f, 0.7518f, -0.6711f, 0.0000f},
      {-1.0477f, -0.1186f, 0.2259f, -37.9419f},
      {-1.0456f, -0.1084f, 0.2160f, -38.3396f},
      {-4.3048f, -1.0318f, 1.1054f, 0.0000f},
      {-4.3619f, -1.0177f, 1.0117f, 79.8312f},
      {-4.3618f, -1.0065f, 1.0001f, 80.7420f},
      {-0.3619f, 0.2410f, -0.2608f, 0.0000f},
      {0.0000f, 0.0000f, 0.0000f, 0.0000f},
      {0.0010f, 0.0060f, -0.0068f, 0.6832f}},
     {{57.0f, 57.0f, 58.0f}, {50.7f, 50.7f, 51.0f}, {51.8f, 54.0f, 54.1f}}},
    // extrapolate
    {{1.000e-06f, 0.000e+00f, 0.010f, 0.000e+00f, 1.208e-02f},
     {{-13.7714f, -6.9114f, 6.6038f, 0.0000f},
      {-0.6760f, 1.4576f, -1.1007f, -91.3709f},
      {-0.7004f, 1.5685f, -1.1814f, -96.4669f},
      {-14.2182f, -6.9644f, 6.6785f, 0.0000f},
      {-5.6361f, -3.3288f, 3.2054f, 36.9109f},
      {-5.6442f, -3.3080f, 3.2133f, 26.7496f},
      {-16.2313f, -8.8252f, 8.4186f, 0.0000f},
      {0.0000f, 0.0000f, 0.0000f, 0.0000f},
      {0.0499f, 0.2118f, -0.1668f, -8.4443f}},
     {{20.4f, 22.4f, 22.4f}, {14.0f, 15.8f, 15.8f}, {21.9f, 23.4f, 23.1f}}},
};

constexpr float kBlackHoleError = 0.25f;

constexpr const char* kNames[kAutoCandidates] = {
    "reverse+none",  "reverse+pullpush", "reverse+andreev", "splat+none",  "splat+pullpush",
    "splat+andreev", "grid+none",        "grid+pullpush",   "grid+andreev"};

bool depth_edge(float z1, float z2) {
    const bool f1 = std::isfinite(z1), f2 = std::isfinite(z2);
    if (f1 != f2) return true;
    if (!f1) return false;
    return std::max(z1, z2) > 1.1f * std::min(z1, z2);
}

}  // namespace

WarpMethod auto_candidate_warp(int candidate) {
    constexpr WarpMethod warps[3] = {WarpMethod::Reverse, WarpMethod::Splat, WarpMethod::Grid};
    return warps[candidate / 3];
}

FillMethod auto_candidate_fill(int candidate) {
    constexpr FillMethod fills[3] = {FillMethod::None, FillMethod::PullPush, FillMethod::Andreev};
    return fills[candidate % 3];
}

const char* auto_candidate_name(int candidate) { return kNames[candidate]; }

FramePredictors survey_predictors(const GBufferView& f) {
    FramePredictors p;
    const int w = f.motion.width, h = f.motion.height;
    if (f.motion.empty()) return p;
    double sum_length = 0.0, gaps = 0.0;
    glm::dvec2 sum(0.0);
    double sum_squares = 0.0;
    std::size_t count = 0;
    const bool depth = !f.depth.empty();
    for (int y = kStep / 2; y < h; y += kStep)
        for (int x = kStep / 2; x < w; x += kStep) {
            const glm::vec2 m = f.motion(x, y);
            if (!std::isfinite(m.x) || !std::isfinite(m.y)) continue;
            p.any_motion |= m.x != 0.0f || m.y != 0.0f;
            sum_length += glm::length(m);
            sum += glm::dvec2(m);
            sum_squares += double(m.x) * m.x + double(m.y) * m.y;
            ++count;
            if (!depth) continue;
            // A depth edge to the right (below) opens or closes a gap as wide as the motions
            // differ across it, over the kStep rows (columns) the pair stands for.
            for (int axis = 0; axis < 2; ++axis) {
                const int qx = x + (axis == 0 ? kStep : 0), qy = y + (axis == 1 ? kStep : 0);
                if (qx >= w || qy >= h) continue;
                const glm::vec2 n = f.motion(qx, qy);
                if (!std::isfinite(n.x) || !std::isfinite(n.y)) continue;
                if (depth_edge(f.depth(x, y), f.depth(qx, qy)))
                    gaps += double(std::abs(m[axis] - n[axis])) * kStep;
            }
        }
    if (count == 0) return p;
    const double n = double(count);
    const glm::dvec2 mean = sum / n;
    p.motion = float(sum_length / n);
    p.spread = float(std::sqrt(std::max(0.0, sum_squares / n - glm::dot(mean, mean))));
    // Half the edges open, the other half close.
    p.disoccluded = float(std::min(1.0, 0.5 * gaps / (n * kStep * kStep)));
    return p;
}

AutoPrediction predict_candidates(const FramePredictors& p, float distance, FrucMode mode) {
    const Model& model = kModels[mode == FrucMode::Interpolate ? 0 : 1];
    const float v = p.motion * distance, sigma = p.spread * distance;
    const float d = std::min(1.0f, p.disoccluded * distance);
    const ErrorModel& e = model.reference;
    const float mse =
        e.floor + e.alpha * (1.0f - std::exp(-e.lambda * v)) + e.beta * sigma + e.kappa * d;
    const float reference = -10.0f * std::log10(std::max(mse, 1e-10f));
    AutoPrediction out;
    for (int c = 0; c < kAutoCandidates; ++c) {
        const int warp = c / 3, fill = c % 3;
        const float* k = model.delta[c];
        float psnr = reference + k[0] + k[1] * v + k[2] * sigma + k[3] * d;
        if (fill == 0 && d > 0.0f) {
            const float candidate_mse = std::pow(10.0f, -psnr / 10.0f);
            psnr = -10.0f * std::log10(candidate_mse + kBlackHoleError * d);
        }
        out.psnr[c] = psnr;
        if (fill == 1 && d == 0.0f) {
            // No hole expected: fill none is not preferred over pull-push (which would not run),
            // in case the sparse survey missed one.
            out.psnr[c - 1] = std::min(out.psnr[c - 1], psnr);
        }
        // A fill runs only on a frame with holes.
        out.cost[c] = model.cost[warp][d > 0.0f ? fill : 0];
    }
    return out;
}

int choose_candidate(const AutoPrediction& prediction, WarpMethod warp, FillMethod fill,
                     const AutoOptions& options) {
    auto allowed = [&](int c) {
        return (warp == WarpMethod::Auto || auto_candidate_warp(c) == warp) &&
               (fill == FillMethod::Auto || auto_candidate_fill(c) == fill);
    };
    float best = -INFINITY;
    for (int c = 0; c < kAutoCandidates; ++c)
        if (allowed(c)) best = std::max(best, prediction.psnr[c]);
    const float target =
        options.budget_db > 0.0f ? std::min(options.budget_db, best) : best - options.slack_db;
    // Equal cost and error (no holes expected: a fill would not run): a fill is kept, in case
    // the sparse survey missed a hole, pull-push first.
    constexpr int kFillPreference[3] = {0, 2, 1};  // none, pullpush, andreev
    int chosen = -1;
    for (int c = 0; c < kAutoCandidates; ++c) {
        if (!allowed(c) || prediction.psnr[c] < target) continue;
        const bool better = chosen < 0 || prediction.cost[c] < prediction.cost[chosen] ||
                            (prediction.cost[c] == prediction.cost[chosen] &&
                             (prediction.psnr[c] > prediction.psnr[chosen] ||
                              (prediction.psnr[c] == prediction.psnr[chosen] &&
                               kFillPreference[c % 3] > kFillPreference[chosen % 3])));
        if (better) chosen = c;
    }
    REPRISE_ASSERT(chosen >= 0);
    return chosen;
}

}  // namespace reprise::warp
