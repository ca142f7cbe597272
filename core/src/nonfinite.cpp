#include "reprise/core/nonfinite.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "reprise/core/parallel.hpp"

namespace reprise {

namespace {

bool bad(float v) { return !std::isfinite(v); }
bool bad(const glm::vec2& v) { return bad(v.x) || bad(v.y); }
bool bad(const glm::vec3& v) { return bad(v.x) || bad(v.y) || bad(v.z); }
bool bad(const glm::vec4& v) { return bad(v.x) || bad(v.y) || bad(v.z) || bad(v.w); }
// Depth: +inf is background, anything else non-finite is unknown.
bool bad_depth(float v) { return std::isnan(v) || v == -std::numeric_limits<float>::infinity(); }

glm::vec4 widen(float v) { return {v, 0.0f, 0.0f, 0.0f}; }
glm::vec4 widen(const glm::vec2& v) { return {v, 0.0f, 0.0f}; }
glm::vec4 widen(const glm::vec3& v) { return {v, 0.0f}; }
glm::vec4 widen(const glm::vec4& v) { return v; }

template <class T>
T narrow(const glm::vec4& v) {
    if constexpr (std::is_same_v<T, float>)
        return v.x;
    else if constexpr (std::is_same_v<T, glm::vec2>)
        return {v.x, v.y};
    else if constexpr (std::is_same_v<T, glm::vec3>)
        return {v.x, v.y, v.z};
    else
        return v;
}

// Whether any of `n` floats is NaN or an infinity (+inf allowed when `positive_inf_ok`): a
// branch-free scan of the exponent bits that the compiler vectorizes, so a clean frame costs one
// streaming read.
bool any_nonfinite(const float* values, std::size_t n, bool positive_inf_ok) {
    constexpr uint32_t kExponent = 0x7f800000u, kPositiveInf = 0x7f800000u;
    uint32_t found = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const uint32_t bits = std::bit_cast<uint32_t>(values[i]);
        found |= uint32_t((bits & kExponent) == kExponent) &
                 uint32_t(!positive_inf_ok || bits != kPositiveInf);
    }
    return found != 0;
}

template <class T, class IsBad>
std::size_t count(ImageView<const T> image, IsBad is_bad, bool positive_inf_ok = false) {
    if (image.empty()) return 0;
    constexpr std::size_t kFloats = sizeof(T) / sizeof(float);
    std::atomic<std::size_t> total{0};
    parallel_for(
        0, image.height,
        [&](int y0, int y1) {
            std::size_t n = 0;
            for (int y = y0; y < y1; ++y) {
                const T* row = image.row(y);
                if (!any_nonfinite(reinterpret_cast<const float*>(row),
                                   std::size_t(image.width) * kFloats, positive_inf_ok))
                    continue;
                for (int x = 0; x < image.width; ++x) n += is_bad(row[x]);
            }
            total += n;
        },
        32);
    return total;
}

enum class Combine { Mean, Max };

// Pull-push over the valid pixels of `image`: each level halves the last, a pixel the mean (or
// max) of its valid children; invalid pixels then take their parent's value, from the top down.
template <class T, class IsBad>
std::size_t pull_push_fill(ImageView<T> image, IsBad is_bad, Combine combine,
                           const glm::vec4& fallback, std::vector<glm::vec4>& values,
                           std::vector<float>& weights, bool positive_inf_ok = false) {
    const std::size_t n = count(ImageView<const T>(image), is_bad, positive_inf_ok);
    if (n == 0) return 0;
    struct Level {
        int w, h;
        std::size_t offset;
    };
    std::vector<Level> levels;  // 1.. (level 0 is the image)
    std::size_t total = 0;
    for (int w = image.width, h = image.height; w > 1 || h > 1;) {
        w = (w + 1) / 2, h = (h + 1) / 2;
        levels.push_back({w, h, total});
        total += std::size_t(w) * std::size_t(h);
    }
    values.resize(total);
    weights.resize(total);
    const auto fetch = [&](int level, int x, int y, glm::vec4& v) -> bool {
        if (level == 0) {
            const T& p = image(x, y);
            if (is_bad(p)) return false;
            v = widen(p);
            return true;
        }
        const Level& l = levels[level - 1];
        const std::size_t i = l.offset + std::size_t(y) * l.w + x;
        if (weights[i] == 0.0f) return false;
        v = values[i];
        return true;
    };
    for (int k = 0; k < int(levels.size()); ++k) {
        const Level& l = levels[k];
        const int below_w = k == 0 ? image.width : levels[k - 1].w;
        const int below_h = k == 0 ? image.height : levels[k - 1].h;
        for (int y = 0; y < l.h; ++y)
            for (int x = 0; x < l.w; ++x) {
                glm::vec4 sum(0.0f), v;
                int valid = 0;
                for (int cy = 2 * y; cy < std::min(2 * y + 2, below_h); ++cy)
                    for (int cx = 2 * x; cx < std::min(2 * x + 2, below_w); ++cx) {
                        if (!fetch(k, cx, cy, v)) continue;
                        if (combine == Combine::Max)
                            sum = valid == 0 ? v : glm::max(sum, v);
                        else
                            sum += v;
                        ++valid;
                    }
                const std::size_t i = l.offset + std::size_t(y) * l.w + x;
                weights[i] = valid > 0 ? 1.0f : 0.0f;
                values[i] = valid == 0 || combine == Combine::Max ? sum : sum / float(valid);
            }
    }
    if (levels.empty()) {  // 1x1
        image(0, 0) = narrow<T>(fallback);
        return n;
    }
    // Push: the top level falls back when nothing was valid, every hole takes its parent.
    {
        const std::size_t top = levels.back().offset;
        if (weights[top] == 0.0f) values[top] = fallback, weights[top] = 1.0f;
    }
    for (int k = int(levels.size()) - 2; k >= 0; --k) {
        const Level& l = levels[k];
        const Level& up = levels[k + 1];
        for (int y = 0; y < l.h; ++y)
            for (int x = 0; x < l.w; ++x) {
                const std::size_t i = l.offset + std::size_t(y) * l.w + x;
                if (weights[i] != 0.0f) continue;
                values[i] = values[up.offset + std::size_t(y / 2) * up.w + x / 2];
                weights[i] = 1.0f;
            }
    }
    const Level& first = levels.front();
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
            if (is_bad(image(x, y)))
                image(x, y) =
                    narrow<T>(values[first.offset + std::size_t(y / 2) * first.w + x / 2]);
    return n;
}

const auto any_bad = [](const auto& v) { return bad(v); };

}  // namespace

NonfiniteCounts count_nonfinite(const GBufferView& frame) {
    NonfiniteCounts c;
    c.color = count(frame.color, any_bad);
    c.depth = count(frame.depth, bad_depth, true);
    c.motion = count(frame.motion, any_bad);
    c.normal = count(frame.normal, any_bad);
    c.frames = c.total() > 0;
    return c;
}

std::size_t NonfiniteRepair::repair_color(ImageView<glm::vec4> color) {
    return pull_push_fill(color, any_bad, Combine::Mean, glm::vec4(0.0f), pyramid_, weights_);
}

std::size_t NonfiniteRepair::repair_depth(ImageView<float> depth) {
    return pull_push_fill(depth, bad_depth, Combine::Max,
                          glm::vec4(std::numeric_limits<float>::infinity()), pyramid_, weights_,
                          true);
}

std::size_t NonfiniteRepair::repair_motion(ImageView<glm::vec2> motion) {
    return pull_push_fill(motion, any_bad, Combine::Mean, glm::vec4(0.0f), pyramid_, weights_);
}

std::size_t NonfiniteRepair::repair_normal(ImageView<glm::vec3> normal) {
    return pull_push_fill(normal, any_bad, Combine::Mean, glm::vec4(0.0f), pyramid_, weights_);
}

std::size_t NonfiniteRepair::repair_ui(ImageView<glm::vec4> ui) {
    const std::size_t n = count(ImageView<const glm::vec4>(ui), any_bad);
    if (n == 0) return 0;
    for (int y = 0; y < ui.height; ++y)
        for (int x = 0; x < ui.width; ++x)
            if (bad(ui(x, y))) ui(x, y) = glm::vec4(0.0f);
    return n;
}

NonfiniteCounts NonfiniteRepair::repair(Frame& frame) {
    NonfiniteCounts c;
    c.color = repair_color(frame.color.view());
    c.depth = repair_depth(frame.depth.view());
    c.motion = repair_motion(frame.motion.view());
    c.normal = repair_normal(frame.normal.view());
    c.ui = repair_ui(frame.ui.view());
    c.frames = c.total() > 0;
    return c;
}

const Frame& NonfiniteRepair::clean(const Frame& frame, NonfiniteCounts& counts) {
    counts = count_nonfinite(frame);
    counts.ui = count(frame.ui.view(), any_bad);
    counts.frames = counts.total() > 0;
    if (counts.total() == 0) return frame;
    copy_.assign(frame);
    copy_.ui.assign(frame.ui.view());
    repair(copy_);
    return copy_;
}

GBufferView NonfiniteRepair::clean(const GBufferView& frame, NonfiniteCounts& counts) {
    counts = count_nonfinite(frame);
    if (counts.total() == 0) return frame;
    copy_.assign(frame);
    repair(copy_);
    return copy_.view();
}

ImageView<const glm::vec4> NonfiniteRepair::clean(ImageView<const glm::vec4> color,
                                                  std::size_t& n) {
    n = count(color, any_bad);
    if (n == 0) return color;
    color_copy_.assign(color);
    repair_color(color_copy_.view());
    return color_copy_.view();
}

std::string describe_nonfinite(const NonfiniteCounts& c) {
    std::string parts;
    const auto part = [&](const char* name, std::size_t n) {
        if (n == 0) return;
        if (!parts.empty()) parts += ", ";
        parts += name;
        parts += ' ';
        parts += std::to_string(n);
    };
    part("colour", c.color);
    part("depth", c.depth);
    part("motion", c.motion);
    part("normal", c.normal);
    part("ui", c.ui);
    return std::to_string(c.total()) + " non-finite values (" + parts + ") in " +
           std::to_string(c.frames) + (c.frames == 1 ? " frame" : " frames") +
           ": colour treated as holes, depth NaN/-inf and motion as unknown, filled from their "
           "neighbours";
}

}  // namespace reprise
