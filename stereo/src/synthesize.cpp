// The second eye: warp the rendered eye (and the history) to the target, merge, fill.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "reprise/core/camera_math.hpp"
#include "reprise/core/parallel.hpp"
#include "reprise/stereo/synthesize.hpp"
#include "reprise/warp/perceptual.hpp"
#include "reprise/warp/silhouettes.hpp"

namespace reprise::stereo {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

bool same_camera(const Camera& a, const Camera& b) {
    return a.view == b.view && a.projection == b.projection;
}

float distance_between(const Camera& a, const Camera& b) {
    return glm::length(glm::vec3(glm::inverse(a.view)[3]) - glm::vec3(glm::inverse(b.view)[3]));
}

}  // namespace

std::size_t drop_moving(const GBufferView& source, float tolerance,
                        ImageView<glm::vec2> displacement) {
    const int w = source.width(), h = source.height();
    if (source.motion.width != w || source.motion.height != h ||
        !(tolerance < std::numeric_limits<float>::infinity()))
        return 0;
    const StaticReprojection to_previous = camera_only_motion(source.camera, w, h);
    const float tolerance2 = tolerance * tolerance;
    std::atomic<std::size_t> dropped{0};
    parallel_for(0, h, [&](int y0, int y1) {
        std::size_t local = 0;
        for (int y = y0; y < y1; ++y) {
            const float* z = source.depth.row(y);
            const glm::vec2* m = source.motion.row(y);
            glm::vec2* d = displacement.row(y);
            for (int x = 0; x < w; ++x) {
                if (std::isnan(d[x].x)) continue;
                const glm::vec2 p(float(x) + 0.5f, float(y) + 0.5f);
                glm::vec2 before;
                bool still = std::isfinite(m[x].x) && std::isfinite(m[x].y) &&
                             to_previous.land(p.x, p.y, z[x], before);
                if (still) {
                    const glm::vec2 error = before - p - m[x];
                    still = glm::dot(error, error) <= tolerance2;
                }
                if (!still) d[x] = glm::vec2(kNaN), ++local;
            }
        }
        dropped += local;
    });
    return dropped.load();
}

std::size_t StereoSynthesizer::warp_into(const GBufferView& given, const Camera& target,
                                         const StereoOptions& o, const warp::WarpTarget& into,
                                         std::size_t& cells, bool& maybe_nonfinite,
                                         std::size_t* moving) {
    GBufferView source =
        o.widen_silhouettes ? warp::widen_silhouettes(given, wide_depth_, wide_motion_) : given;
    if (o.perceptual) source.color = warp::encode_perceptual(source.color, encoded_color_);
    const int w = source.width(), h = source.height();
    displacement_.resize(w, h);
    target_depth_.resize(w, h);
    // The displacement reads the source's depth; the warp carries the target's depth along.
    stereo_displacement(source, target, displacement_.view(), target_depth_.view());
    if (moving) *moving = drop_moving(source, o.history_moving_tolerance, displacement_.view());
    const GBufferView moved{.color = source.color,
                            .depth = target_depth_.view(),
                            .motion = displacement_.view(),
                            .camera = source.camera};
    if (o.warp == StereoWarp::Splat) {
        maybe_nonfinite = true;  // the splat does not count them
        return warp::splat(moved, 1.0f, into, o.splat);
    }
    const warp::GridStats stats = grid_.warp(moved, 1.0f, into, o.grid);
    cells += stats.cells;
    maybe_nonfinite = maybe_nonfinite || stats.nonfinite > 0;
    return stats.covered;
}

StereoStats StereoSynthesizer::synthesize(const GBufferView& given, const Camera& target,
                                          Frame& out, const StereoOptions& o,
                                          const GBufferView* given_history) {
    const int w = given.width(), h = given.height();
    REPRISE_ASSERT(w > 0 && h > 0);
    REPRISE_ASSERT(given.depth.width == w && given.depth.height == h);
    StereoStats stats;
    // NaN and infinities (but background depth) are repaired before anything is warped.
    const GBufferView rendered = rendered_repair_.clean(given, stats.nonfinite);
    GBufferView history_view;
    const GBufferView* history = nullptr;
    if (given_history) {
        NonfiniteCounts found;
        history_view = history_repair_.clean(*given_history, found);
        history = &history_view;
        stats.nonfinite += found;
    }
    out.motion.clear();
    out.normal.clear();
    out.id.clear();
    out.camera = target;
    covered_.resize(w, h);
    const std::size_t n = std::size_t(w) * std::size_t(h);

    const bool history_usable = history && history->width() == w && history->height() == h &&
                                history->depth.width == w && history->depth.height == h;
    // The same viewpoint: nothing to warp.
    const GBufferView* exact =
        same_camera(rendered.camera, target) ? &rendered
        : history_usable && same_camera(history->camera, target) && rendered.motion_is_zero()
            ? history
            : nullptr;
    if (exact) {
        out.color.assign(exact->color);
        out.depth.assign(exact->depth);
        covered_.fill(uint8_t(exact == &rendered));
        stats.covered = exact == &rendered ? n : 0;
        stats.from_history = exact == &rendered ? 0 : n;
        return stats;
    }

    out.color.resize(w, h);
    out.depth.resize(w, h);
    bool maybe_nonfinite = false;  // else everything written is finite: no last pass needed
    stats.covered =
        warp_into(rendered, target, o, {out.color.view(), out.depth.view(), {}, covered_.view()},
                  stats.cells, maybe_nonfinite);
    stats.holes = n - stats.covered;

    // Pixels only a grid triangle stretched over a disocclusion covered come from the history
    // where it saw them, and are otherwise left to pull-push or the patch fill (Andreev's fill
    // measured worse than the stretched triangle there; docs/benchmarks.md).
    const bool refill = o.fill == StereoFill::PullPush || o.fill == StereoFill::Patch;
    valid_.resize(w, h);
    std::size_t stretched = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const uint8_t c = covered_.data()[i];
        stretched += c == warp::kCoveredStretched;
        valid_.data()[i] = refill && c == warp::kCoveredStretched ? 0 : c;
    }
    stats.stretched = stretched;
    ImageView<const uint8_t> valid = valid_.view();
    std::size_t history_holes_filled = 0;
    if (history_usable) {
        history_color_.resize(w, h);
        history_depth_.resize(w, h);
        history_covered_.resize(w, h);
        warp_into(*history, target, o,
                  {history_color_.view(), history_depth_.view(), {}, history_covered_.view()},
                  stats.cells, maybe_nonfinite, &stats.history_moving);
        const bool closer = o.history_replaces && distance_between(history->camera, target) <
                                                      distance_between(rendered.camera, target);
        const float tol = o.history_depth_tolerance;
        std::size_t taken = 0, holes_taken = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const uint8_t seen = history_covered_.data()[i];
            if (!seen) continue;
            const float zh = history_depth_.data()[i], zc = out.depth.data()[i];
            // A stretched pixel takes only what the history saw unstretched.
            const bool stretched_here = covered_.data()[i] == warp::kCoveredStretched;
            const bool hole = !stretched_here && !valid_.data()[i];
            const bool better = hole || (stretched_here && seen != warp::kCoveredStretched);
            const bool same = zh == zc || std::abs(zh - zc) <= tol * std::min(zh, zc);
            if (better || (closer && same)) {
                out.color.data()[i] = history_color_.data()[i];
                out.depth.data()[i] = zh;
                valid_.data()[i] = 1;
                ++taken;
                holes_taken += hole;
            }
        }
        stats.from_history = taken;
        history_holes_filled = holes_taken;
    }

    // What the made eye sees past the rendered eye's view at the left and right edges continues
    // the row (the fills, which prefer the farthest samples, pulled the sky down across that
    // strip; docs/benchmarks.md). The splat eye keeps the fill's, on the CPU and the GPU.
    if (o.warp == StereoWarp::Grid && o.fill != StereoFill::None)
        stats.border = warp::continue_border_rows(out.color.view(), out.depth.view(), valid_.view(),
                                                  out.color.width());
    warp::FillStats filled;
    if (o.fill == StereoFill::PullPush)
        filled = pull_push_.fill(out.color.view(), valid, out.depth.view());
    else if (o.fill == StereoFill::Andreev)
        filled = andreev_.fill(out.color.view(), valid, out.depth.view());
    else if (o.fill == StereoFill::Patch)
        filled = patch_.fill(out.color.view(), valid, out.depth.view());
    else {
        filled.holes = stats.holes - history_holes_filled;
        filled.unfilled = filled.holes;
    }
    stats.filled = filled.holes - filled.unfilled;
    stats.unfilled = filled.unfilled;
    if (o.perceptual) warp::decode_perceptual(out.color.view());
    // Non-finite colour carried from the input (the fill replaces RGB only) becomes 0; holes the
    // warp left and the fill could not fill are 0 already.
    if (!maybe_nonfinite) return stats;
    parallel_for(0, h, [&](int y0, int y1) {
        for (std::size_t i = std::size_t(y0) * w; i < std::size_t(y1) * w; ++i) {
            glm::vec4& c = out.color.data()[i];
            if (!(std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z) &&
                  std::isfinite(c.w)))
                c = glm::vec4(0.0f);
        }
    });
    return stats;
}

StereoStats synthesize_eye(const GBufferView& rendered, const Camera& target,
                           const StereoOptions& options, Frame& out, const GBufferView* history) {
    StereoSynthesizer synthesizer;
    return synthesizer.synthesize(rendered, target, out, options, history);
}

}  // namespace reprise::stereo
