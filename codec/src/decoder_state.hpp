#pragma once
// What a decoder holds between packets; the encoder reads it to resume a stream.
#include <deque>
#include <memory>
#include <vector>

#include "internal.hpp"
#include "reprise/core/nonfinite.hpp"

namespace reprise::codec {

struct Decoder::State {
    DecoderOptions options;
    SequenceParams sp;
    bool started = false;
    // Shared with the DecodedFrames handed out; a picture one of them still holds is not
    // decoded into again.
    std::shared_ptr<Picture> refs[kReferences];
    bool have_newest = false;
    uint32_t newest = 0;
    struct Output {
        std::shared_ptr<const Picture> picture;
        Image<glm::vec4> color;
        Image<glm::u8vec4> display;
        double fps = 0.0;
    };
    std::deque<Output> queue;
    // Colour buffers handed back, reused for output.
    std::vector<Image<glm::vec4>> spare;
    std::vector<Image<glm::u8vec4>> spare_display;
    StreamStats stats;
    NonfiniteRepair repair;
    std::shared_ptr<Picture> scratch;
    Workspace work;
    DecodedFrame as_frame;  // receive_frame(Frame&)'s, keeping its colour buffer

    State() {
        for (auto& p : refs) p = std::make_shared<Picture>();
        scratch = std::make_shared<Picture>();
    }

    int slot_of(uint32_t frame) const { return held_slot(refs, frame); }
};

}  // namespace reprise::codec
