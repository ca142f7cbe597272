#include "reprise/net/fragment.hpp"

#include <algorithm>

namespace reprise::net {

std::size_t fragment_packet(std::span<const uint8_t> packet, uint32_t frame, int64_t pose_time_us,
                            const FecOptions& options,
                            std::vector<std::vector<uint8_t>>& messages) {
    REPRISE_ASSERT(!packet.empty() && packet.size() <= kMaxPacketBytes);
    const std::size_t size =
        std::clamp<std::size_t>(options.fragment_payload, 16, kMaxFragmentPayload);
    const std::size_t count = (packet.size() + size - 1) / size;
    REPRISE_ASSERT(count <= kMaxFragments);
    const int group = std::clamp(options.group, 0, 255);
    const std::size_t groups = group > 0 ? (count + group - 1) / group : 0;
    if (messages.size() < count + groups) messages.resize(count + groups);
    FragmentMessage m{.frame = frame,
                      .total_size = uint32_t(packet.size()),
                      .data_count = uint16_t(count),
                      .fragment_size = uint16_t(size),
                      .group_size = uint8_t(group),
                      .pose_time_us = pose_time_us};
    for (std::size_t i = 0; i < count; ++i) {
        m.index = uint16_t(i);
        m.kind = FragmentKind::Data;
        m.payload = packet.subspan(i * size, std::min(size, packet.size() - i * size));
        messages[i].resize(kMaxPlaintext);
        messages[i].resize(encode(m, messages[i]));
    }
    for (std::size_t g = 0; g < groups; ++g) {
        // As long as the group's first (longest) fragment: a one-fragment packet's parity is
        // no longer than the packet.
        std::vector<uint8_t>& out = messages[count + g];
        out.resize(kFragmentHeaderSize + std::min(size, packet.size() - g * group * size));
        std::fill(out.begin() + kFragmentHeaderSize, out.end(), 0);
        for (std::size_t i = g * group; i < std::min(count, (g + 1) * group); ++i) {
            const std::size_t n =
                std::min(out.size() - kFragmentHeaderSize, packet.size() - i * size);
            const uint8_t* src = packet.data() + i * size;
            for (std::size_t b = 0; b < n; ++b) out[kFragmentHeaderSize + b] ^= src[b];
        }
        m.index = uint16_t(g);
        m.kind = FragmentKind::Parity;
        m.payload = {};
        // Header written over the front; the XOR payload already sits behind it.
        std::vector<uint8_t> header(kFragmentHeaderSize + 1);
        const std::size_t written = encode(m, header);
        REPRISE_ASSERT(written == kFragmentHeaderSize);
        std::copy(header.begin(), header.begin() + kFragmentHeaderSize, out.begin());
    }
    return count + groups;
}

Reassembler::Reassembler(const ReassemblerOptions& options) : options_(options) {
    options_.slots = std::clamp(options_.slots, 1, 64);
    slots_.resize(options_.slots);
}

std::size_t Reassembler::bytes_held() const {
    std::size_t n = 0;
    for (const Slot& s : slots_)
        n += s.data.capacity() + s.parity.capacity() + s.have.capacity() + s.have_parity.capacity();
    return n;
}

void Reassembler::abandon_older_than(uint32_t frame, std::vector<uint32_t>& abandoned) {
    for (Slot& s : slots_)
        if (s.used && s.frame < frame) {
            s.used = false;
            ++stats_.abandoned;
            abandoned.push_back(s.frame);
        }
}

bool Reassembler::try_complete(Slot& s) {
    if (s.received < s.count && s.group > 0) {
        const std::size_t groups = (s.count + s.group - 1) / s.group;
        for (std::size_t g = 0; g < groups; ++g) {
            if (!s.have_parity[g]) continue;
            const std::size_t begin = g * s.group,
                              end = std::min<std::size_t>(s.count, begin + s.group);
            std::size_t missing = 0, which = 0;
            for (std::size_t i = begin; i < end; ++i)
                if (!s.have[i]) ++missing, which = i;
            if (missing != 1) continue;
            uint8_t* dst = s.data.data() + which * s.payload;
            std::copy_n(s.parity.data() + g * s.payload, s.payload, dst);
            for (std::size_t i = begin; i < end; ++i) {
                if (i == which) continue;
                const uint8_t* src = s.data.data() + i * s.payload;
                for (std::size_t b = 0; b < s.payload; ++b) dst[b] ^= src[b];
            }
            s.have[which] = 1;
            ++s.received;
            ++stats_.recovered;
        }
    }
    return s.received == s.count;
}

bool Reassembler::add(const FragmentMessage& f, Reassembled& out,
                      std::vector<uint32_t>& abandoned) {
    ++stats_.fragments;
    if (int64_t(f.frame) <= newest_done_ || f.total_size > options_.max_packet_bytes) {
        ++stats_.stale;
        return false;
    }
    Slot* slot = nullptr;
    for (Slot& s : slots_)
        if (s.used && s.frame == f.frame) slot = &s;
    if (slot && (slot->total != f.total_size || slot->count != f.data_count ||
                 slot->group != f.group_size || slot->payload != f.fragment_size)) {
        ++stats_.inconsistent;
        return false;
    }
    if (!slot) {
        for (Slot& s : slots_)
            if (!s.used) slot = &s;
        if (!slot) {
            slot = &slots_[0];
            for (Slot& s : slots_)
                if (s.frame < slot->frame) slot = &s;
            if (slot->frame > f.frame) {  // older than everything held: not worth a slot
                ++stats_.stale;
                return false;
            }
            ++stats_.abandoned;
            abandoned.push_back(slot->frame);
        }
        Slot& s = *slot;
        s.used = true;
        s.frame = f.frame;
        s.total = f.total_size;
        s.count = f.data_count;
        s.group = f.group_size;
        s.payload = f.fragment_size;
        s.pose_time_us = f.pose_time_us;
        s.received = 0;
        const std::size_t groups = s.group ? (s.count + s.group - 1) / s.group : 0;
        s.data.assign(std::size_t(s.count) * s.payload, 0);
        s.parity.assign(groups * s.payload, 0);
        s.have.assign(s.count, 0);
        s.have_parity.assign(groups, 0);
    }
    Slot& s = *slot;
    if (f.kind == FragmentKind::Data) {
        if (s.have[f.index]) {
            ++stats_.duplicates;
            return false;
        }
        std::copy(f.payload.begin(), f.payload.end(),
                  s.data.begin() + std::size_t(f.index) * s.payload);
        s.have[f.index] = 1;
        ++s.received;
    } else {
        if (s.have_parity[f.index]) {
            ++stats_.duplicates;
            return false;
        }
        std::copy(f.payload.begin(), f.payload.end(),
                  s.parity.begin() + std::size_t(f.index) * s.payload);
        s.have_parity[f.index] = 1;
    }
    if (!try_complete(s)) return false;
    s.used = false;
    newest_done_ = s.frame;
    out.frame = s.frame;
    out.pose_time_us = s.pose_time_us;
    out.data = std::span<const uint8_t>(s.data.data(), s.total);
    abandon_older_than(s.frame, abandoned);
    return true;
}

}  // namespace reprise::net
