#pragma once
// What a decoder holds between packets; the encoder reads it to resume a stream.
#include <deque>
#include <vector>

#include "internal.hpp"
#include "reprise/core/nonfinite.hpp"

namespace reprise::codec {

struct Decoder::State {
    DecoderOptions options;
    SequenceParams sp;
    bool started = false;
    Picture refs[kReferences];
    bool have_newest = false;
    uint32_t newest = 0;
    std::deque<Frame> queue;
    std::vector<Frame> spare;  // frames handed back by receive_frame, reused for output
    StreamStats stats;
    NonfiniteRepair repair;
    Picture scratch;
    Workspace work;

    int slot_of(uint32_t frame) const { return held_slot(refs, frame); }
};

}  // namespace reprise::codec
