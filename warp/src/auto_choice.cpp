// `--warp auto --fill auto`: error and cost models per candidate setting, in the manner of
// Sitthi-amorn et al. 2008 (error saturating exponentially with how far a value is reused, cost
// linear in the work), evaluated at run time on predictors surveyed before warping.
#include <algorithm>
#include <cmath>

#include "reprise/warp/fruc.hpp"

namespace reprise::warp {

namespace {

constexpr int kStep = 8;  // the survey: every 8th pixel of every 8th row

// Expected mean squared error of display values at warp distance t (input periods):
//   floor + alpha (1 - exp(-lambda v)) + beta sigma + kappa[fill] d,
// v = motion t, sigma = spread t, d = disoccluded t (predictors of FramePredictors). Fitted by
// scripts/fit_auto.py to `reprise bench fruc` runs on the built-in scenes (docs/benchmarks.md).
struct ErrorModel {
    float floor, alpha, lambda, beta;
    float kappa[3];  // none, pullpush, andreev
};
struct Model {
    ErrorModel error[3];    // reverse, splat, grid
    float cost[3][3];       // ns per pixel: [warp][fill]
    float fill_cost_holes;  // a fill runs only where there are holes: share of its cost kept
};

// [mode] interpolate, extrapolate
constexpr Model kModels[2] = {
    // interpolate
    {{{1.0e-5f, 2.0e-3f, 0.05f, 1.0e-5f, {0.08f, 0.02f, 0.02f}},
      {1.0e-5f, 4.0e-3f, 0.05f, 2.0e-5f, {0.08f, 0.03f, 0.03f}},
      {1.0e-5f, 2.2e-3f, 0.05f, 1.0e-5f, {0.08f, 0.02f, 0.02f}}},
     {{60.0f, 75.0f, 75.0f}, {25.0f, 40.0f, 40.0f}, {40.0f, 55.0f, 55.0f}},
     1.0f},
    // extrapolate
    {{{1.0e-5f, 3.0e-3f, 0.05f, 2.0e-5f, {0.10f, 0.02f, 0.02f}},
      {1.0e-5f, 6.0e-3f, 0.05f, 3.0e-5f, {0.10f, 0.03f, 0.03f}},
      {1.0e-5f, 3.0e-3f, 0.05f, 2.0e-5f, {0.10f, 0.02f, 0.02f}}},
     {{70.0f, 85.0f, 85.0f}, {25.0f, 40.0f, 40.0f}, {45.0f, 60.0f, 60.0f}},
     1.0f},
};

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
    AutoPrediction out;
    for (int c = 0; c < kAutoCandidates; ++c) {
        const int warp = c / 3, fill = c % 3;
        const ErrorModel& e = model.error[warp];
        const float mse = e.floor + e.alpha * (1.0f - std::exp(-e.lambda * v)) + e.beta * sigma +
                          e.kappa[fill] * d;
        out.psnr[c] = -10.0f * std::log10(std::max(mse, 1e-10f));
        // A fill costs nothing on a frame without holes.
        const float fill_share = d > 0.0f ? 1.0f : 0.0f;
        out.cost[c] = model.cost[warp][0] + fill_share * model.fill_cost_holes *
                                                (model.cost[warp][fill] - model.cost[warp][0]);
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
    int chosen = -1;
    for (int c = 0; c < kAutoCandidates; ++c) {
        if (!allowed(c) || prediction.psnr[c] < target) continue;
        if (chosen < 0 || prediction.cost[c] < prediction.cost[chosen] ||
            (prediction.cost[c] == prediction.cost[chosen] &&
             prediction.psnr[c] > prediction.psnr[chosen]))
            chosen = c;
    }
    REPRISE_ASSERT(chosen >= 0);
    return chosen;
}

}  // namespace reprise::warp
