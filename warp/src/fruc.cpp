#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include "fruc_stages.hpp"
#include "reprise/core/memory_limit.hpp"
#include "reprise/core/metrics.hpp"
#include "reprise/core/parallel.hpp"
#include "reprise/warp/shot_change.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace reprise::warp {

namespace {

// Output frames waiting for receive(), in a ring whose slots keep their buffers: a slot handed
// out by receive() gets the caller's previous frame in exchange, so the steady state reuses the
// same images and allocates nothing.
class FrameQueue {
public:
    bool empty() const { return count_ == 0; }
    // The next slot to fill (its old contents are to be overwritten).
    Frame& push() {
        if (count_ == slots_.size()) grow();
        Frame& f = slots_[(head_ + count_) % slots_.size()];
        ++count_;
        return f;
    }
    Frame& back() { return slots_[(head_ + count_ - 1) % slots_.size()]; }
    std::size_t size() const { return count_; }
    void truncate(std::size_t count) { count_ = std::min(count_, count); }
    void pop_into(Frame& out) {
        std::swap(out, slots_[head_]);
        head_ = (head_ + 1) % slots_.size();
        --count_;
    }

private:
    void grow() {
        std::vector<Frame> bigger(std::max<std::size_t>(4, 2 * slots_.size()));
        for (std::size_t i = 0; i < slots_.size(); ++i)
            std::swap(bigger[i], slots_[(head_ + i) % slots_.size()]);
        slots_.swap(bigger);
        head_ = 0;
    }
    std::vector<Frame> slots_;
    std::size_t head_ = 0, count_ = 0;
};

template <class T>
void size_like(Image<T>& image, const ImageView<const T>& like) {
    if (like.empty())
        image.clear();
    else
        image.resize(like.width, like.height);
}

// Row bytes into one or two destinations with streaming stores where everything is 16-byte
// aligned: the copies are larger than any cache and not read back soon, so their lines need not
// be fetched first.
void stream_row(const void* from, void* to, void* to2, std::size_t bytes) {
#if defined(__SSE2__)
    const auto aligned = [](const void* p) {
        return reinterpret_cast<std::uintptr_t>(p) % 16 == 0;
    };
    if (aligned(from) && aligned(to) && (!to2 || aligned(to2))) {
        const __m128i* s = static_cast<const __m128i*>(from);
        __m128i* d = static_cast<__m128i*>(to);
        __m128i* d2 = static_cast<__m128i*>(to2);
        const std::size_t n = bytes / 16;
        for (std::size_t i = 0; i < n; ++i) {
            const __m128i v = _mm_load_si128(s + i);
            _mm_stream_si128(d + i, v);
            if (d2) _mm_stream_si128(d2 + i, v);
        }
        const std::size_t done = n * 16;
        std::memcpy(static_cast<char*>(to) + done, static_cast<const char*>(from) + done,
                    bytes - done);
        if (to2)
            std::memcpy(static_cast<char*>(to2) + done, static_cast<const char*>(from) + done,
                        bytes - done);
        return;
    }
#endif
    std::memcpy(to, from, bytes);
    if (to2) std::memcpy(to2, from, bytes);
}

// Rows [y0, y1) of `from` into `to` and, when not null, `to2` (both sized like it).
template <class T>
void copy_rows(ImageView<const T> from, Image<T>& to, int y0, int y1, Image<T>* to2 = nullptr) {
    for (int y = y0; y < y1; ++y)
        stream_row(from.row(y), &to(0, y), to2 ? &(*to2)(0, y) : nullptr,
                   std::size_t(from.width) * sizeof(T));
#if defined(__SSE2__)
    _mm_sfence();  // streaming stores are weakly ordered
#endif
}

// `from` into `to` (sized like it), rows in parallel.
template <class T>
void copy_image(ImageView<const T> from, Image<T>& to) {
    size_like(to, from);
    parallel_for(
        0, from.height, [&](int y0, int y1) { copy_rows(from, to, y0, y1); }, 64);
}

}  // namespace

struct FrameRateConverter::State {
    int factor;
    FrucOptions options;
    FrucCounters counters;
    FrucScratch scratch;
    Frame previous;  // colour, depth, motion and ids of the last input (no normals)
    bool has_previous = false;
    bool previous_starts_shot = false;  // its motion reaches back into another shot: unusable
    uint64_t previous_key = 0;          // the last input's key (FrucScratch::input_key)
    FrameQueue ready;
    FrucOptions chosen;  // `options` with an auto warp or fill resolved for one frame
    NonfiniteRepair nonfinite;

    float motion_scale() const { return 1.0f / float(factor); }

    bool automatic() const {
        return options.warp == WarpMethod::Auto || options.fill == FillMethod::Auto;
    }

    // The options for one frame `distance` input periods from the frame `p` was surveyed on.
    const FrucOptions& resolve(const FramePredictors& p, float distance, FrucMode mode) {
        if (!automatic()) return options;
        const AutoPrediction prediction = predict_candidates(p, distance, mode);
        const int c = choose_candidate(prediction, options.warp, options.fill, options.auto_choice);
        ++counters.auto_chosen[c];
        for (int k = 0; k < kAutoCandidates; ++k) {
            const bool allowed =
                (options.warp == WarpMethod::Auto || auto_candidate_warp(k) == options.warp) &&
                (options.fill == FillMethod::Auto || auto_candidate_fill(k) == options.fill);
            counters.auto_left_out[k] += allowed && prediction.psnr[k] > prediction.psnr[c];
        }
        chosen = options;
        chosen.warp = auto_candidate_warp(c);
        chosen.fill = auto_candidate_fill(c);
        return chosen;
    }

    // A shot change between `previous` and `frame`: the frame's camera says so, or its size
    // changed, or, when its camera does not say, its pixels show it (is_cut).
    bool starts_shot(const Frame& frame) {
        if (previous.width() != frame.width() || previous.height() != frame.height()) return true;
        if (frame.camera.cut != Cut::Unknown) {
            ++counters.cut_tests_skipped;
            return frame.camera.cut == Cut::Yes;
        }
        return is_cut(frame);
    }

    // Most of the new frame has no counterpart in the old one, or what does differs in colour.
    bool is_cut(const Frame& frame) {
        return shot_change(frame, previous, options.cut_misses, options.cut_color,
                           scratch.shot_change)
            .cut;
    }

    // Stamps the camera and time of a made frame (its motion is already per output period).
    void finish(Frame& out, const Camera& a, const Camera& b, double fps, float s,
                float previous_s) {
        Camera before = camera_between(a, b, previous_s);
        out.camera = camera_between(a, b, s);
        out.camera.prev_view = before.view;
        out.camera.prev_projection = before.projection;
        out.fps = fps > 0 ? fps * factor : 0.0;
        out.normal.clear();
        out.id.clear();
        ++counters.outputs;
    }

    // The camera of the instant one frame period before `f` (from its prev_* matrices).
    static Camera previous_instant(const Camera& camera, double fps) {
        Camera c = camera;
        c.view = camera.prev_view;
        c.projection = camera.prev_projection;
        c.time = camera.time - (fps > 0 ? 1.0 / fps : 0.0);
        return c;
    }

    // The input itself as an output (colour, depth, motion per output period: what made frames
    // carry) and, when `kept` is given, copied there as the next previous frame, in one pass.
    void emit_input(const Frame& frame, Frame* kept) {
        Frame& out = ready.push();
        const GBufferView in = frame.view();
        size_like(out.color, in.color);
        size_like(out.depth, in.depth);
        size_like(out.motion, in.motion);
        out.normal.clear();
        out.id.clear();
        if (kept) {
            size_like(kept->color, in.color);
            size_like(kept->depth, in.depth);
            size_like(kept->motion, in.motion);
            size_like(kept->id, in.id);
            kept->normal.clear();
        }
        const float scale = motion_scale();
        auto rows_of = [](const auto& view, int y0, int y1) {
            return std::pair(std::min(y0, view.height), std::min(y1, view.height));
        };
        parallel_for(
            0, frame.height(),
            [&](int y0, int y1) {
                copy_rows(in.color, out.color, y0, y1, kept ? &kept->color : nullptr);
                auto [d0, d1] = rows_of(in.depth, y0, y1);
                copy_rows(in.depth, out.depth, d0, d1, kept ? &kept->depth : nullptr);
                auto [m0, m1] = rows_of(in.motion, y0, y1);
                if (kept) copy_rows(in.motion, kept->motion, m0, m1);
                for (int y = m0; y < m1; ++y) {
                    const glm::vec2* from = in.motion.row(y);
                    glm::vec2* to = &out.motion(0, y);
                    for (int x = 0; x < in.motion.width; ++x) to[x] = from[x] * scale;
                }
                if (kept) {
                    auto [i0, i1] = rows_of(in.id, y0, y1);
                    copy_rows(in.id, kept->id, i0, i1);
                }
            },
            32);
        out.camera = frame.camera;
        out.fps = frame.fps > 0 ? frame.fps * factor : 0.0;
        if (kept) {
            kept->camera = frame.camera;
            kept->fps = frame.fps;
            if (frame.ui.empty())
                kept->ui.clear();
            else
                copy_image(frame.ui.view(), kept->ui);
        }
        attach_ui(out, frame, false);
    }

    // The UI of `nearest` (an input) on a frame in the queue: in its ui channels or, with
    // composite_ui, drawn over its colour.
    void attach_ui(Frame& out, const Frame& nearest, bool made) {
        if (nearest.ui.empty() || out.color.empty()) {
            out.ui.clear();
            return;
        }
        if (options.composite_ui) {
            composite_ui(out.color.view(), nearest.ui.view(), out.color.view());
            out.ui.clear();
        } else {
            copy_image(nearest.ui.view(), out.ui);
        }
        counters.ui_frames += made;
    }

    // Colour and depth of `frame` with zero motion.
    void emit_copy(const GBufferView& frame, const Camera& a, const Camera& b, double fps,
                   float s) {
        Frame& out = ready.push();
        copy_image(frame.color, out.color);
        copy_image(frame.depth, out.depth);
        out.motion.assign(frame.width(), frame.height(), glm::vec2(0.0f));
        finish(out, a, b, fps, s, s - 1.0f / factor);
    }
};

FrameRateConverter::FrameRateConverter() : state_(std::make_unique<State>()) { state_->factor = 2; }

Status FrameRateConverter::create(int factor, const FrucOptions& options,
                                  FrameRateConverter& converter) {
    REPRISE_TRY(check_fruc_factor(factor));
    REPRISE_TRY(check_fruc_options(options));
    FrameRateConverter made;
    made.state_->factor = factor;
    made.state_->options = options;
    converter = std::move(made);
    return {};
}

FrameRateConverter::~FrameRateConverter() = default;
FrameRateConverter::FrameRateConverter(FrameRateConverter&&) noexcept = default;
FrameRateConverter& FrameRateConverter::operator=(FrameRateConverter&&) noexcept = default;

const FrucCounters& FrameRateConverter::counters() const { return state_->counters; }

void FrameRateConverter::refine_region(Image<uint8_t>& mask) const {
    state_->scratch.refiner.region(mask, state_->previous.width(), state_->previous.height());
}

Result FrameRateConverter::receive(Frame& out) {
    State& st = *state_;
    if (st.ready.empty()) return Result::NeedMoreData;
    st.ready.pop_into(out);
    return Result::Ok;
}

Status FrameRateConverter::send(const Frame& frame) { return send_frame(frame, nullptr); }

Status FrameRateConverter::send(Frame&& frame) { return send_frame(frame, &frame); }

Status FrameRateConverter::send_frame(const Frame& given, Frame* owned) {
    State& st = *state_;
    const int w = given.width(), h = given.height();
    REPRISE_TRY(check_image_size(w, h, "fruc input frame"));
    // History, scratch and made frames: `reprise fruc --factor 2` peaked at 282 bytes a pixel
    // (RSS at 1920x1080 minus 960x540), 44 of them the caller's input frame.
    // Since then the two widened inputs (FrucScratch::wide_*): 24 more, and their encoded
    // colour (FrucScratch::encoded_color, FrucOptions::perceptual): 32, counted.
    REPRISE_TRY(check_image_memory(w, h, 296, "fruc"));
    auto sized = [&](auto& image) {
        return image.empty() || (image.width() == w && image.height() == h);
    };
    if (!sized(given.depth) || !sized(given.motion))
        return Status::error("fruc input frame: depth or motion size differs from colour");
    if (!sized(given.ui)) return Status::error("fruc input frame: ui size differs from colour");
    // What an error of the backend puts back: the converter as it was before this frame.
    const FrucCounters counters_before = st.counters;
    const std::size_t queued_before = st.ready.size();
    auto undone_unless = [&](const Status& made) {
        if (!made.ok()) {
            st.ready.truncate(queued_before);
            st.counters = counters_before;
        }
        return made;
    };
    NonfiniteCounts found;
    const Frame& frame = owned ? *owned : st.nonfinite.clean(given, found);
    if (owned) found = st.nonfinite.repair(*owned);
    st.counters.nonfinite += found;
    ++st.counters.inputs;
    st.scratch.refiner.forget_region();
    const bool warpable = !frame.depth.empty() && !frame.motion.empty();
    const bool cut = st.has_previous && st.starts_shot(frame);
    st.counters.cuts += cut;
    const int k_max = st.factor;

    const uint64_t key = next_frame_key();
    if (st.options.mode == FrucMode::Interpolate)
        st.scratch.input_key[0] = st.previous_key, st.scratch.input_key[1] = key;
    else
        st.scratch.input_key[0] = key, st.scratch.input_key[1] = 0;
    const double fps = frame.fps;
    const float scale = st.motion_scale();
    FramePredictors predicted;  // surveyed only for an auto choice
    if (st.options.mode == FrucMode::Interpolate) {
        if (st.has_previous) {
            const Frame& a = st.previous;
            if (st.automatic() && warpable) predicted = survey_predictors(cut ? a : frame);
            const bool a_warpable =
                !a.depth.empty() && !a.motion.empty() && !st.previous_starts_shot;
            const Camera a_before = State::previous_instant(a.camera, a.fps);
            // A still pair is copied unless refinement finds its pictures differ (a moving
            // light, say): then it is interpolated like any other.
            bool still = false, still_refined = false;
            if (!cut && warpable && frame.view().motion_is_zero()) {
                still = true;
                if (st.options.refine.enabled && a_warpable) {
                    const auto start = std::chrono::steady_clock::now();
                    still_refined = st.scratch.refiner.pictures_differ(a, frame, st.options.refine);
                    st.counters.refine_ms += std::chrono::duration<double, std::milli>(
                                                 std::chrono::steady_clock::now() - start)
                                                 .count();
                }
            }
            for (int k = 1; k < k_max; ++k) {
                float s = float(k) / float(k_max);
                if (cut && !a_warpable) {
                    st.emit_copy(a, a.camera, frame.camera, fps, s);
                } else if (cut) {
                    // The new shot starts at the new frame: the frames before it belong to the
                    // old one, continued from its last frame alone; nothing is blended across.
                    Frame& out = st.ready.push();
                    REPRISE_TRY(undone_unless(extrapolate_frame(
                        a, s, scale, st.resolve(predicted, s, FrucMode::Extrapolate), st.scratch,
                        out, st.counters)));
                    st.finish(out, a_before, a.camera, a.fps, 1.0f + s, 1.0f + s - 1.0f / k_max);
                } else if (!warpable || a.depth.empty() || a.motion.empty()) {
                    st.emit_copy(s < 0.5f ? a.view() : frame.view(), a.camera, frame.camera, fps,
                                 s);
                } else if (still && !still_refined) {
                    ++st.counters.copied_still;
                    st.counters.refine_skipped += st.options.refine.enabled;
                    st.emit_copy(frame, a.camera, frame.camera, fps, s);
                } else {
                    Frame& out = st.ready.push();
                    if (st.options.backend && a_warpable) {
                        // The inputs the CPU's warps would take.
                        REPRISE_TRY(undone_unless(st.options.backend->interpolate(
                            backend_input(a, 0, st.options, st.scratch, st.counters),
                            backend_input(frame, 1, st.options, st.scratch, st.counters), s, scale,
                            st.options, out, st.counters, st.scratch.input_key[0],
                            st.scratch.input_key[1])));
                    } else {
                        interpolate_frame(
                            a, frame, s, a_warpable, scale,
                            st.resolve(predicted, std::min(s, 1.0f - s), FrucMode::Interpolate),
                            st.scratch, out, st.counters);
                    }
                    st.finish(out, a.camera, frame.camera, fps, s, s - 1.0f / k_max);
                }
                st.attach_ui(st.ready.back(), s >= 0.5f ? frame : a, true);
            }
        }
        st.emit_input(frame, owned ? nullptr : &st.previous);
    } else {
        // With a backend, which may fail, the frame becomes `previous` only once its frames are
        // made (a failed send leaves the converter as it was).
        st.emit_input(frame, owned || st.options.backend ? nullptr : &st.previous);
        if (st.automatic() && warpable && !cut) predicted = survey_predictors(frame);
        const Camera before = State::previous_instant(frame.camera, fps);
        for (int k = 1; k < k_max; ++k) {
            float s = float(k) / float(k_max);
            if (cut || !warpable) {
                st.emit_copy(frame, before, frame.camera, fps, 1.0f + s);
            } else if (frame.view().motion_is_zero()) {
                ++st.counters.copied_still;
                st.emit_copy(frame, before, frame.camera, fps, 1.0f + s);
            } else {
                Frame& out = st.ready.push();
                REPRISE_TRY(undone_unless(extrapolate_frame(
                    frame, s, scale, st.resolve(predicted, s, FrucMode::Extrapolate), st.scratch,
                    out, st.counters)));
                st.finish(out, before, frame.camera, fps, 1.0f + s, 1.0f + s - 1.0f / k_max);
            }
            st.attach_ui(st.ready.back(), frame, true);
        }
    }
    if (owned)
        std::swap(st.previous, *owned);  // the caller gets the old buffers to refill
    else if (st.options.mode == FrucMode::Extrapolate && st.options.backend)
        st.previous = frame;
    st.has_previous = true;
    st.previous_starts_shot = cut;
    st.previous_key = key;
    return {};
}

}  // namespace reprise::warp
