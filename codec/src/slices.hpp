#pragma once
// A section split into independently coded slices (bands of macroblock rows): each slice is
// preceded by its byte length, so slices are coded and decoded in parallel and the result does
// not depend on the thread count.
#include <cstring>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "reprise/core/byte_io.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::codec {

using SliceModels = std::vector<std::vector<uint8_t>>;  // per slice: its adaptive models' bytes

// Version 20: the slices of an inter frame's section start from the adaptive models that the same
// slices of its reference picture's section ended with (`from`); a key frame's start fresh. The
// picture being made (`to`) keeps each slice's models at its end, and the reference's where the
// section codes no slices.
struct ModelCarry {
    const SliceModels* from = nullptr;
    SliceModels* to = nullptr;

    // `to` as the reference's models, for `slices` slices.
    void pass_on(int slices) const {
        if (!to) return;
        *to = from ? *from : SliceModels{};
        to->resize(std::size_t(slices));
    }
    template <class Models>
    void load(int slice, Models& m) const {
        static_assert(std::is_trivially_copyable_v<Models>);
        if (from && std::size_t(slice) < from->size() && (*from)[slice].size() == sizeof(Models))
            std::memcpy(&m, (*from)[slice].data(), sizeof(Models));
        else
            m = Models{};
    }
    // After pass_on: each slice writes its own entry, so slices in parallel may save.
    template <class Models>
    void save(int slice, const Models& m) const {
        if (!to || std::size_t(slice) >= to->size()) return;
        (*to)[slice].resize(sizeof(Models));
        std::memcpy((*to)[slice].data(), &m, sizeof(Models));
    }
};

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
