#pragma once
// Little-endian writers (appending to a vector, or into a fixed buffer) and a bounds-checked
// reader of untrusted bytes: the codec's container and the network protocol share them.
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "reprise/core/status.hpp"

namespace reprise {

// The encodings; Sink provides put(const uint8_t*, std::size_t).
template <class Sink>
class LittleEndianWriter {
public:
    void u8(uint8_t v) { put(&v, 1); }
    void u16(uint16_t v) { word(v, 2); }
    void u32(uint32_t v) { word(v, 4); }
    void u64(uint64_t v) { word(v, 8); }
    void f32(float v) {
        uint32_t u;
        std::memcpy(&u, &v, 4);
        u32(u);
    }
    void f64(double v) {
        uint64_t u;
        std::memcpy(&u, &v, 8);
        u64(u);
    }
    // 7 bits a byte, low first; the high bit says another byte follows.
    void varint(uint64_t v) {
        while (v >= 0x80) {
            u8(uint8_t(v | 0x80));
            v >>= 7;
        }
        u8(uint8_t(v));
    }
    void bytes(std::span<const uint8_t> b) { put(b.data(), b.size()); }

private:
    void word(uint64_t v, int n) {
        uint8_t b[8];
        for (int i = 0; i < n; ++i) b[i] = uint8_t(v >> (8 * i));
        put(b, std::size_t(n));
    }
    void put(const uint8_t* p, std::size_t n) { static_cast<Sink*>(this)->put(p, n); }
};

// Appends to a growing vector.
class ByteWriter : public LittleEndianWriter<ByteWriter> {
public:
    explicit ByteWriter(std::vector<uint8_t>& out) : out_(out) {}
    std::size_t size() const { return out_.size(); }  // of the whole vector
    void put(const uint8_t* p, std::size_t n) {
        const std::size_t at = out_.size();
        out_.resize(at + n);
        if (n) std::memcpy(out_.data() + at, p, n);
    }

private:
    std::vector<uint8_t>& out_;
};

// Writes into a fixed buffer from its start; overflow is a contract violation of the caller.
class FixedByteWriter : public LittleEndianWriter<FixedByteWriter> {
public:
    explicit FixedByteWriter(std::span<uint8_t> out) : out_(out) {}
    std::size_t size() const { return pos_; }  // bytes written
    void put(const uint8_t* p, std::size_t n) {
        REPRISE_ASSERT(n <= out_.size() - pos_);
        if (n) std::memcpy(out_.data() + pos_, p, n);
        pos_ += n;
    }

private:
    std::span<uint8_t> out_;
    std::size_t pos_ = 0;
};

// Every read checks what remains; after the first failure all reads return 0 (or nothing),
// remaining() is 0, ok() is false and error() names `what`, the byte and the reason.
class ByteReader {
public:
    explicit ByteReader(std::span<const uint8_t> in, std::string what = {})
        : in_(in), what_(std::move(what)) {}
    uint8_t u8() { return uint8_t(get(1)); }
    uint16_t u16() { return uint16_t(get(2)); }
    uint32_t u32() { return uint32_t(get(4)); }
    uint64_t u64() { return get(8); }
    float f32() {
        const uint32_t u = u32();
        float v;
        std::memcpy(&v, &u, 4);
        return v;
    }
    double f64() {
        const uint64_t u = u64();
        double v;
        std::memcpy(&v, &u, 8);
        return v;
    }
    uint64_t varint() {
        uint64_t v = 0;
        for (int shift = 0; shift < 64; shift += 7) {
            const uint8_t b = u8();
            v |= uint64_t(b & 0x7F) << shift;
            if (!(b & 0x80)) return v;
        }
        fail("varint longer than 10 bytes");
        return 0;
    }
    // The next n bytes (empty and failed when fewer remain).
    std::span<const uint8_t> bytes(uint64_t n) {
        if (!ok_ || n > remaining()) {
            fail("needs " + std::to_string(n) + " bytes");
            return {};
        }
        auto s = in_.subspan(pos_, std::size_t(n));
        pos_ += std::size_t(n);
        return s;
    }
    std::size_t remaining() const { return ok_ ? in_.size() - pos_ : 0; }
    std::size_t position() const { return pos_; }
    bool ok() const { return ok_; }
    const std::string& error() const { return error_; }
    void fail(const std::string& why) {
        if (ok_) error_ = what_ + " at byte " + std::to_string(pos_) + ": " + why;
        ok_ = false;
    }

private:
    uint64_t get(int n) {
        if (!ok_ || remaining() < std::size_t(n)) {
            if (ok_)
                fail("truncated (needs " + std::to_string(n) + " bytes, " +
                     std::to_string(remaining()) + " left)");
            return 0;
        }
        uint64_t v = 0;
        for (int i = 0; i < n; ++i) v |= uint64_t(in_[pos_ + i]) << (8 * i);
        pos_ += std::size_t(n);
        return v;
    }
    std::span<const uint8_t> in_;
    std::size_t pos_ = 0;
    bool ok_ = true;
    std::string what_, error_;
};

}  // namespace reprise
