#pragma once
// Motion for colour-only input (plain renders, video): OpenCV's DIS optical flow between
// consecutive frames stands in for rendered motion, one depth for every pixel for the missing Z.
#include <memory>

#include "reprise/core/frame.hpp"

namespace reprise::cli {

class FlowMotion {
public:
    FlowMotion();
    ~FlowMotion();
    // Gives `frame` backward motion (p + motion = p in the previous frame given, zero for the
    // first) where it has none, and depth 1 where it has none.
    void complete(Frame& frame);

private:
    struct State;
    std::unique_ptr<State> state_;
};

}  // namespace reprise::cli
