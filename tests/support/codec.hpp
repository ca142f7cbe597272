// Test support: a sequence through one encoder, packets and reconstructions kept; and back.
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
    codec::Encoder encoder;
    EXPECT_TRUE(codec::Encoder::create(options, encoder).ok());
    for (const Frame& f : frames) {
        Status s = encoder.send_frame(f);
        EXPECT_TRUE(s.ok()) << s.message();
        codec::Packet p;
        EXPECT_EQ(encoder.receive_packet(p), Result::Ok);
        c.packets.push_back(std::move(p));
        c.reconstructions.push_back(encoder.reconstruction());
    }
    c.stats = encoder.stats();
    return c;
}

inline std::vector<Frame> decode_all(const std::vector<codec::Packet>& packets) {
    codec::Decoder decoder;
    std::vector<Frame> out;
    for (const codec::Packet& p : packets) {
        Status s = decoder.send_packet(p.data);
        EXPECT_TRUE(s.ok()) << s.message();
        Frame f;
        while (decoder.receive_frame(f) == Result::Ok) out.push_back(std::move(f));
    }
    return out;
}

}  // namespace reprise::test
