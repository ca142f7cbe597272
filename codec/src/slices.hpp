#pragma once
// A section split into independently coded slices (bands of macroblock rows): each slice is
// preceded by its byte length, so slices are coded and decoded in parallel and the result does
// not depend on the thread count.
#include <span>
#include <string>
#include <vector>

#include "reprise/core/byte_io.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::codec {

template <class CodeSlice>  // void(int slice, std::vector<uint8_t>& bytes)
void encode_slices(int count, std::vector<std::vector<uint8_t>>& scratch, std::vector<uint8_t>& out,
                   const CodeSlice& code) {
    scratch.resize(count);
    parallel_for(
        0, count,
        [&](int s0, int s1) {
            for (int s = s0; s < s1; ++s) {
                scratch[s].clear();
                code(s, scratch[s]);
            }
        },
        1);
    ByteWriter w(out);
    for (int s = 0; s < count; ++s) {
        w.varint(scratch[s].size());
        w.bytes(scratch[s]);
    }
}

// Decodes every slice in parallel; an error naming the first corrupt one.
template <class DecodeSlice>  // bool(int slice, std::span<const uint8_t> bytes)
Status decode_slices(const std::vector<std::span<const uint8_t>>& slices, const char* section,
                     const DecodeSlice& decode) {
    const int count = int(slices.size());
    std::vector<uint8_t> ok(count, 0);
    parallel_for(
        0, count,
        [&](int s0, int s1) {
            for (int s = s0; s < s1; ++s) ok[s] = decode(s, slices[s]);
        },
        1);
    for (int s = 0; s < count; ++s)
        if (!ok[s])
            return Status::error(std::string(section) + ": slice " + std::to_string(s) +
                                 " is corrupt");
    return {};
}

// Splits the rest of `r` into `count` slices; false (with r failed) when lengths overrun.
inline bool read_slices(ByteReader& r, int count, std::vector<std::span<const uint8_t>>& slices) {
    slices.resize(count);
    for (int s = 0; s < count; ++s) slices[s] = r.bytes(r.varint());
    if (r.ok() && r.remaining())
        r.fail(std::to_string(r.remaining()) + " bytes after the last slice");
    return r.ok();
}

}  // namespace reprise::codec
