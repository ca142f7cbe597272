#include <cmath>
#include <deque>
#include <utility>

#include "fruc_stages.hpp"
#include "reprise/core/metrics.hpp"

namespace reprise::warp {

struct FrameRateConverter::State {
    int factor;
    FrucOptions options;
    FrucCounters counters;
    FrucScratch scratch;
    Frame previous;
    bool has_previous = false;
    bool previous_starts_shot = false;  // its motion reaches back into another shot: unusable
    std::deque<Frame> ready;
    std::vector<Frame> spare;  // output frames handed back to be reused

    Frame take_spare() {
        if (spare.empty()) return {};
        Frame f = std::move(spare.back());
        spare.pop_back();
        return f;
    }

    // A shot change between `previous` and `frame`: most of the new frame has no counterpart in
    // the old one, or what does differs in colour.
    bool is_cut(const Frame& frame) {
        const int w = frame.width(), h = frame.height();
        if (previous.width() != w || previous.height() != h) return true;
        if (frame.depth.empty() || frame.motion.empty() || previous.depth.empty()) return false;
        scratch.reprojected.resize(w, h);
        scratch.valid.resize(w, h);
        ReprojectCounts counts = reproject(frame, previous, payload_of(std::as_const(previous.color).view()),
                                           payload_of(scratch.reprojected.view()),
                                           scratch.valid.view(), {.depth_tolerance = 0.05f});
        const double pixels = double(w) * h;
        const double lost = double(counts.behind + counts.occluded + counts.other_id + counts.invalid);
        if (lost > options.cut_misses * pixels) return true;
        if (counts.hits == 0) return counts.offscreen > options.cut_misses * pixels;
        // Mean display-colour difference over the hits, on every 4th pixel of every 4th row.
        double difference = 0.0;
        std::size_t sampled = 0;
        for (int y = 0; y < h; y += 4)
            for (int x = 0; x < w; x += 4) {
                if (!scratch.valid(x, y)) continue;
                glm::vec4 a = frame.color(x, y), b = scratch.reprojected(x, y);
                for (int k = 0; k < 3; ++k)
                    difference += std::abs(linear_to_srgb(a[k]) - linear_to_srgb(b[k]));
                ++sampled;
            }
        if (sampled == 0) return false;
        return difference / (3.0 * double(sampled)) > options.cut_color;
    }

    // Scales motion from input periods to output periods and stamps the camera and time.
    void finish(Frame& out, const Frame& a, const Frame& b, float s, float previous_s) {
        const float scale = 1.0f / float(factor);
        for (std::size_t i = 0, n = out.motion.pixel_count(); i < n; ++i)
            out.motion.data()[i] *= scale;
        Camera before = camera_between(a.camera, b.camera, previous_s);
        out.camera = camera_between(a.camera, b.camera, s);
        out.camera.prev_view = before.view;
        out.camera.prev_projection = before.projection;
        out.fps = b.fps > 0 ? b.fps * factor : 0.0;
        out.normal.clear();
        out.id.clear();
    }

    void push(Frame&& out) {
        ready.push_back(std::move(out));
        ++counters.outputs;
    }

    // The camera of the instant one frame period before `f` (from its prev_* matrices).
    static Camera previous_instant(const Frame& f) {
        Camera c = f.camera;
        c.view = f.camera.prev_view;
        c.projection = f.camera.prev_projection;
        c.time = f.camera.time - (f.fps > 0 ? 1.0 / f.fps : 0.0);
        return c;
    }
    static Frame camera_only(const Camera& camera) {
        Frame f;
        f.camera = camera;
        return f;
    }

    void emit_input(const Frame& frame) {
        Frame out = take_spare();
        out = frame;
        if (!out.motion.empty()) {
            const float scale = 1.0f / float(factor);
            for (std::size_t i = 0, n = out.motion.pixel_count(); i < n; ++i)
                out.motion.data()[i] *= scale;
        }
        if (frame.fps > 0) out.fps = frame.fps * factor;
        ready.push_back(std::move(out));
    }

    void emit_copy(const Frame& frame, const Frame& a, const Frame& b, float s) {
        Frame out = take_spare();
        out.color = frame.color;
        out.depth = frame.depth;
        out.motion.resize(frame.width(), frame.height(), glm::vec2(0.0f));
        finish(out, a, b, s, s - 1.0f / factor);
        push(std::move(out));
    }
};

FrameRateConverter::FrameRateConverter(int factor, const FrucOptions& options)
    : state_(std::make_unique<State>()) {
    REPRISE_ASSERT(factor >= 1);
    state_->factor = factor;
    state_->options = options;
}

FrameRateConverter::~FrameRateConverter() = default;

const FrucCounters& FrameRateConverter::counters() const { return state_->counters; }

bool FrameRateConverter::receive(Frame& out) {
    State& st = *state_;
    if (st.ready.empty()) return false;
    if (!out.color.empty()) st.spare.push_back(std::move(out));
    out = std::move(st.ready.front());
    st.ready.pop_front();
    return true;
}

Status FrameRateConverter::send(const Frame& frame) {
    State& st = *state_;
    const int w = frame.width(), h = frame.height();
    REPRISE_TRY(check_image_size(w, h, "fruc input frame"));
    auto sized = [&](auto& image) { return image.empty() || (image.width() == w && image.height() == h); };
    if (!sized(frame.depth) || !sized(frame.motion))
        return Status::error("fruc input frame: depth or motion size differs from colour");
    ++st.counters.inputs;
    const bool warpable = !frame.depth.empty() && !frame.motion.empty();
    const bool cut = st.has_previous && st.is_cut(frame);
    st.counters.cuts += cut;
    const int k_max = st.factor;

    if (st.options.mode == FrucMode::Interpolate) {
        if (st.has_previous) {
            const Frame& a = st.previous;
            const bool a_warpable = !a.depth.empty() && !a.motion.empty() && !st.previous_starts_shot;
            const Frame a_before = State::camera_only(State::previous_instant(a));
            for (int k = 1; k < k_max; ++k) {
                float s = float(k) / float(k_max);
                if (cut && !a_warpable) {
                    st.emit_copy(a, a, frame, s);
                } else if (cut) {
                    // The new shot starts at the new frame: the frames before it belong to the
                    // old one, continued from its last frame alone; nothing is blended across.
                    Frame out = st.take_spare();
                    extrapolate_frame(a, s, st.options, st.scratch, out, st.counters);
                    st.finish(out, a_before, a, 1.0f + s, 1.0f + s - 1.0f / k_max);
                    st.push(std::move(out));
                } else if (!warpable || a.depth.empty() || a.motion.empty()) {
                    st.emit_copy(s < 0.5f ? a : frame, a, frame, s);
                } else if (motion_is_zero(frame)) {
                    ++st.counters.copied_still;
                    st.emit_copy(frame, a, frame, s);
                } else {
                    Frame out = st.take_spare();
                    interpolate_frame(a, frame, s, a_warpable, st.options, st.scratch, out, st.counters);
                    st.finish(out, a, frame, s, s - 1.0f / k_max);
                    st.push(std::move(out));
                }
            }
        }
        st.emit_input(frame);
    } else {
        st.emit_input(frame);
        const Frame before = State::camera_only(State::previous_instant(frame));
        for (int k = 1; k < k_max; ++k) {
            float s = float(k) / float(k_max);
            if (cut || !warpable) {
                st.emit_copy(frame, before, frame, 1.0f + s);
            } else if (motion_is_zero(frame)) {
                ++st.counters.copied_still;
                st.emit_copy(frame, before, frame, 1.0f + s);
            } else {
                Frame out = st.take_spare();
                extrapolate_frame(frame, s, st.options, st.scratch, out, st.counters);
                st.finish(out, before, frame, 1.0f + s, 1.0f + s - 1.0f / k_max);
                st.push(std::move(out));
            }
        }
    }
    st.previous = frame;
    st.has_previous = true;
    st.previous_starts_shot = cut;
    return {};
}

}  // namespace reprise::warp
