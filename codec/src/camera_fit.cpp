// Camera fit: Levenberg-Marquardt on the reprojection error of a pixel grid, parameters a
// rotation vector, a translation in units of the median depth and the log of a focal scale,
// with rounds of trimming at 3 robust sigmas so that moving objects drop out.
#include "camera_fit.hpp"

#include "least_squares.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

namespace reprise::codec {

namespace {

constexpr int kGridSamples = 2000;
constexpr int kMinSamples = 12;
constexpr int kRounds = 5;
constexpr double kFloorPx = 0.1;  // the smallest trimming threshold
constexpr double kExplainedPx = 0.25;

struct Sample {
    double u, v;    // pixel centre relative to the image centre (v downwards)
    double z;       // depth in units of the median depth; 0 = background
    double tu, tv;  // where the point was in the previous frame
};

using fit::kBehindPx;
using fit::Params;  // rotation vector, translation, log focal scale
using fit::rotation;

struct Model {
    double fx, fy;  // focal lengths in pixels at scale 1

    // Reprojection error of every sample under q.
    void residuals(const Params& q, const std::vector<Sample>& s, std::vector<double>& r) const {
        const glm::dmat3 rot = rotation(q[0], q[1], q[2]);
        const glm::dvec3 t(q[3], q[4], q[5]);
        const double scale = std::exp(q[6]);
        const double gx = fx * scale, gy = fy * scale;
        r.resize(2 * s.size());
        for (std::size_t i = 0; i < s.size(); ++i) {
            const Sample& p = s[i];
            const bool background = p.z == 0.0;
            const double z = background ? 1.0 : p.z;
            glm::dvec3 point = rot * glm::dvec3(p.u / gx * z, -p.v / gy * z, -z);
            if (!background) point += t;
            if (!(point.z < -1e-9)) {
                r[2 * i] = r[2 * i + 1] = kBehindPx;
                continue;
            }
            r[2 * i] = gx * point.x / -point.z - p.tu;
            r[2 * i + 1] = -gy * point.y / -point.z - p.tv;
        }
    }
};

}  // namespace

glm::mat4 assumed_projection(int width, int height) {
    const double aspect = double(std::max(width, 1)) / double(std::max(height, 1));
    return glm::mat4(glm::perspective(glm::radians(50.0), aspect, 0.1, 1000.0));
}

CameraFit fit_camera(ImageView<const float> depth, ImageView<const glm::vec2> motion,
                     const glm::mat4& projection, bool fit_focal) {
    CameraFit fit;
    fit.projection = projection;
    const int w = depth.width, h = depth.height;
    const glm::mat4& p = projection;
    if (depth.empty() || motion.width != w || motion.height != h) return fit;
    if (!(p[2][3] == -1.0f && p[3][3] == 0.0f && p[2][0] == 0.0f && p[2][1] == 0.0f &&
          p[0][0] > 0.0f && p[1][1] > 0.0f && std::isfinite(p[0][0]) && std::isfinite(p[1][1])))
        return fit;

    // The grid: cells of step x step pixels, each sampled at its centre pixel.
    const int step = std::max(1, int(std::sqrt(double(w) * h / kGridSamples)));
    std::vector<Sample> samples;
    std::vector<double> depths;
    for (int y = step / 2; y < h; y += step)
        for (int x = step / 2; x < w; x += step) {
            const float z = depth(x, y);
            const glm::vec2 m = motion(x, y);
            if (!(z > 0.0f) || !std::isfinite(m.x) || !std::isfinite(m.y)) continue;
            const double u = x + 0.5 - 0.5 * w, v = y + 0.5 - 0.5 * h;
            samples.push_back({u, v, std::isfinite(z) ? double(z) : 0.0, u + m.x, v + m.y});
            if (std::isfinite(z)) depths.push_back(z);
        }
    fit.samples = int(samples.size());
    if (fit.samples < kMinSamples) return fit;
    // Translation in units of the median depth keeps every parameter of the same order.
    const double unit = depths.empty() ? 1.0 : std::max(fit::median(depths), 1e-30);
    for (Sample& s : samples) s.z /= unit;

    const Model model{double(p[0][0]) * w / 2.0, double(p[1][1]) * h / 2.0};
    const int n = fit_focal ? 7 : 6;
    Params q{};
    std::vector<uint8_t> inlier(samples.size(), 1);
    std::vector<double> r, norms(samples.size());
    for (int round = 0; round < kRounds; ++round) {
        fit::refine(model, samples, inlier, n, q);
        model.residuals(q, samples, r);
        for (std::size_t i = 0; i < samples.size(); ++i)
            norms[i] = std::hypot(r[2 * i], r[2 * i + 1]);
        const double threshold = std::max(3.0 * 1.4826 * fit::median(norms), kFloorPx);
        for (std::size_t i = 0; i < samples.size(); ++i) inlier[i] = norms[i] <= threshold;
    }
    for (double v : q)
        if (!std::isfinite(v)) return fit;
    if (std::abs(q[6]) > 2.0) return fit;  // a focal length 7 times off: not a camera

    // Kept only when it explains at least as many samples as no camera motion does.
    int explained = 0, still = 0;
    double sum = 0.0;
    for (std::size_t i = 0; i < samples.size(); ++i) {
        explained += norms[i] <= kExplainedPx;
        still +=
            std::hypot(samples[i].tu - samples[i].u, samples[i].tv - samples[i].v) <= kExplainedPx;
        if (inlier[i]) {
            ++fit.inliers;
            sum += norms[i] * norms[i];
        }
    }
    if (explained < still || fit.inliers < kMinSamples) return fit;
    fit.rms_px = std::sqrt(sum / fit.inliers);
    const glm::dmat3 rot = rotation(q[0], q[1], q[2]);
    fit.relative = glm::dmat4(rot);
    fit.relative[3] = glm::dvec4(q[3] * unit, q[4] * unit, q[5] * unit, 1.0);
    if (fit_focal) {
        const float scale = float(std::exp(q[6]));
        fit.projection[0][0] *= scale;
        fit.projection[1][1] *= scale;
    }
    fit.ok = true;
    return fit;
}

}  // namespace reprise::codec
