#include "flow_motion.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

namespace reprise::cli {

struct FlowMotion::State {
    cv::Ptr<cv::DISOpticalFlow> flow =
        cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_MEDIUM);
    cv::Mat grey, previous_grey, backward;
};

FlowMotion::FlowMotion() : state_(std::make_unique<State>()) {}
FlowMotion::~FlowMotion() = default;

void FlowMotion::complete(Frame& frame) {
    State& st = *state_;
    const int w = frame.width(), h = frame.height();
    if (frame.depth.empty()) frame.depth.assign(w, h, 1.0f);
    // Grey display levels: the flow is estimated on what a viewer sees.
    st.grey.create(h, w, CV_8U);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const glm::vec4 c = frame.color(x, y);
            const float luma = 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b;
            const float display =
                linear_to_srgb(std::isfinite(luma) ? std::clamp(luma, 0.0f, 1.0f) : 0.0f);
            st.grey.at<uint8_t>(y, x) = uint8_t(display * 255.0f + 0.5f);
        }
    if (frame.motion.empty()) {
        frame.motion.assign(w, h, glm::vec2(0.0f));
        if (st.previous_grey.size() == st.grey.size()) {
            // Each pair from scratch (DIS would start from a flow field it is given): a run
            // that starts mid-sequence (--resume, --range) then makes the same motion.
            st.backward.release();
            st.flow->calc(st.grey, st.previous_grey, st.backward);  // now(p) ~ before(p + flow)
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    const cv::Vec2f m = st.backward.at<cv::Vec2f>(y, x);
                    frame.motion(x, y) = glm::vec2(m[0], m[1]);
                }
        }
    }
    cv::swap(st.grey, st.previous_grey);
}

}  // namespace reprise::cli
