// The second eye: warp the rendered eye (and the history) to the target, merge, fill.
#include <algorithm>
#include <cmath>
#include <limits>

#include "reprise/core/parallel.hpp"
#include "reprise/stereo/synthesize.hpp"

namespace reprise::stereo {

namespace {

bool same_camera(const Camera& a, const Camera& b) {
    return a.view == b.view && a.projection == b.projection;
}

bool all_still(const Frame& f) {
    if (f.motion.empty()) return false;
    const glm::vec2* m = f.motion.data();
    for (std::size_t i = 0; i < f.motion.pixel_count(); ++i)
        if (m[i].x != 0.0f || m[i].y != 0.0f) return false;
    return true;
}

float distance_between(const Camera& a, const Camera& b) {
    return glm::length(glm::vec3(glm::inverse(a.view)[3]) - glm::vec3(glm::inverse(b.view)[3]));
}

template <class T>
void copy_into(Image<T>& to, const Image<T>& from) {
    if (to.width() != from.width() || to.height() != from.height()) to.resize(from.width(), from.height());
    std::copy(from.data(), from.data() + from.pixel_count(), to.data());
}

}  // namespace

std::size_t StereoSynthesizer::warp_into(const Frame& source, const Camera& target,
                                         const StereoOptions& o, const warp::WarpTarget& into) {
    const int w = source.width(), h = source.height();
    copy_into(scratch_.color, source.color);
    if (scratch_.depth.width() != w || scratch_.depth.height() != h) scratch_.depth.resize(w, h);
    if (scratch_.motion.width() != w || scratch_.motion.height() != h) scratch_.motion.resize(w, h);
    scratch_.camera = source.camera;
    // The displacement reads the source's depth; the warp carries the target's depth along.
    stereo_displacement(source, target, scratch_.motion.view(), scratch_.depth.view());
    if (o.warp == StereoWarp::Splat) {
        warp::splat(scratch_, 1.0f, into, o.splat);
        return 0;
    }
    return grid_.warp(scratch_, 1.0f, into, o.grid).cells;
}

StereoStats StereoSynthesizer::synthesize(const Frame& rendered, const Camera& target, Frame& out,
                                          const StereoOptions& o, const Frame* history) {
    const int w = rendered.width(), h = rendered.height();
    REPRISE_ASSERT(w > 0 && h > 0);
    REPRISE_ASSERT(rendered.depth.width() == w && rendered.depth.height() == h);
    StereoStats stats;
    out.motion.clear();
    out.normal.clear();
    out.id.clear();
    out.camera = target;
    out.fps = rendered.fps;
    if (covered_.width() != w || covered_.height() != h) covered_.resize(w, h);
    const std::size_t n = std::size_t(w) * std::size_t(h);

    const bool history_usable = history && history->width() == w && history->height() == h &&
                                history->depth.width() == w && history->depth.height() == h;
    // The same viewpoint: nothing to warp.
    const Frame* exact = same_camera(rendered.camera, target) ? &rendered
                         : history_usable && same_camera(history->camera, target) && all_still(rendered)
                             ? history
                             : nullptr;
    if (exact) {
        copy_into(out.color, exact->color);
        copy_into(out.depth, exact->depth);
        std::fill(covered_.data(), covered_.data() + n, uint8_t(exact == &rendered));
        stats.covered = exact == &rendered ? n : 0;
        stats.from_history = exact == &rendered ? 0 : n;
        return stats;
    }

    out.color.resize(w, h);
    out.depth.resize(w, h);
    stats.cells += warp_into(rendered, target, o,
                             {out.color.view(), out.depth.view(), {}, covered_.view()});
    for (std::size_t i = 0; i < n; ++i) stats.covered += covered_.data()[i];
    stats.holes = n - stats.covered;

    if (valid_.width() != w || valid_.height() != h) valid_.resize(w, h);
    std::copy(covered_.data(), covered_.data() + n, valid_.data());
    if (history_usable) {
        if (history_color_.width() != w || history_color_.height() != h) {
            history_color_.resize(w, h);
            history_depth_.resize(w, h);
            history_covered_.resize(w, h);
        }
        stats.cells += warp_into(*history, target, o,
                                 {history_color_.view(), history_depth_.view(), {}, history_covered_.view()});
        const bool closer = o.history_replaces && distance_between(history->camera, target) <
                            distance_between(rendered.camera, target);
        const float tol = o.history_depth_tolerance;
        std::size_t taken = 0;
        for (std::size_t i = 0; i < n; ++i) {
            if (!history_covered_.data()[i]) continue;
            const float zh = history_depth_.data()[i], zc = out.depth.data()[i];
            const bool hole = !valid_.data()[i];
            const bool same = zh == zc || std::abs(zh - zc) <= tol * std::min(zh, zc);
            if (hole || (closer && same)) {
                out.color.data()[i] = history_color_.data()[i];
                out.depth.data()[i] = zh;
                valid_.data()[i] = 1;
                ++taken;
            }
        }
        stats.from_history = taken;
    }

    warp::FillStats filled;
    if (o.fill == StereoFill::PullPush)
        filled = pull_push_.fill(out.color.view(), valid_.view(), out.depth.view());
    else if (o.fill == StereoFill::Andreev)
        filled = andreev_.fill(out.color.view(), valid_.view(), out.depth.view());
    else {
        for (std::size_t i = 0; i < n; ++i) filled.holes += !valid_.data()[i];
        filled.unfilled = filled.holes;
    }
    stats.filled = filled.holes - filled.unfilled;
    stats.unfilled = filled.unfilled;
    // Whatever could not be filled (and non-finite alpha carried from the input) becomes 0.
    parallel_for(0, h, [&](int y0, int y1) {
        for (std::size_t i = std::size_t(y0) * w; i < std::size_t(y1) * w; ++i) {
            glm::vec4& c = out.color.data()[i];
            if (!(std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z) && std::isfinite(c.w)))
                c = glm::vec4(0.0f);
        }
    });
    return stats;
}

StereoStats synthesize_eye(const Frame& rendered, const Camera& target, const StereoOptions& options,
                           Frame& out, const Frame* history) {
    StereoSynthesizer synthesizer;
    return synthesizer.synthesize(rendered, target, out, options, history);
}

}  // namespace reprise::stereo
