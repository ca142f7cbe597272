// Test support: a sequence through one encoder, packets and reconstructions kept.
#pragma once

#include <gtest/gtest.h>

#include <vector>

#include "reprise/codec/codec.hpp"

namespace reprise::test {

struct Coded {
    std::vector<codec::Packet> packets;
    std::vector<Frame> reconstructions;
    codec::StreamStats stats;
};

inline Coded encode_all(const std::vector<Frame>& frames, const codec::EncoderOptions& options) {
    Coded c;
    codec::Encoder encoder(options);
    for (const Frame& f : frames) {
        Status s = encoder.send_frame(f);
        EXPECT_TRUE(s.ok()) << s.message();
        codec::Packet p;
        EXPECT_EQ(encoder.receive_packet(p), codec::Result::Ok);
        c.packets.push_back(std::move(p));
        c.reconstructions.push_back(encoder.reconstruction());
    }
    c.stats = encoder.stats();
    return c;
}

}  // namespace reprise::test
