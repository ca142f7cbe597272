#include "fruc_stages.hpp"
#include "reprise/warp/extrapolate.hpp"

namespace reprise::warp {

struct PoseExtrapolator::State {
    FrucOptions options;
    FrucScratch scratch;
    FrucCounters counters;
    uint64_t caller_key = 0, key = 0;  // the caller's last frame key and its unique one
};

PoseExtrapolator::PoseExtrapolator(const FrucOptions& options) : state_(std::make_unique<State>()) {
    state_->options = options;
    state_->options.mode = FrucMode::Extrapolate;
}
PoseExtrapolator::~PoseExtrapolator() = default;
PoseExtrapolator::PoseExtrapolator(PoseExtrapolator&&) noexcept = default;
PoseExtrapolator& PoseExtrapolator::operator=(PoseExtrapolator&&) noexcept = default;

Status PoseExtrapolator::extrapolate(const GBufferView& frame, const glm::mat4& view,
                                     const glm::mat4& projection, float periods, Frame& out,
                                     uint64_t frame_key) {
    REPRISE_ASSERT(periods >= 0.0f);
    State& s = *state_;
    // The caller's keys are its own (a count of decoded frames): each new one becomes a key
    // unique in the process, so that a backend shared with others keeps the frames apart.
    if (frame_key != s.caller_key || frame_key == 0) {
        s.caller_key = frame_key;
        s.key = frame_key ? next_frame_key() : 0;
    }
    s.scratch.input_key[0] = s.key;
    const FrucCounters before = s.counters;
    const Status made = extrapolate_to_camera(frame, view, projection, periods, 1.0f, s.options,
                                              s.scratch, out, s.counters);
    if (!made.ok()) {
        s.counters = before;
        return made;
    }
    ++s.counters.inputs;
    ++s.counters.outputs;
    out.camera = frame.camera;
    out.camera.prev_view = frame.camera.view;
    out.camera.prev_projection = frame.camera.projection;
    out.camera.view = view;
    out.camera.projection = projection;
    out.camera.jitter = glm::vec2(0.0f);
    return {};
}

const FrucCounters& PoseExtrapolator::counters() const { return state_->counters; }

}  // namespace reprise::warp
