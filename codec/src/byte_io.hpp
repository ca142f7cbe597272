#pragma once
// Little-endian writing into a growing buffer and bounds-checked reading of untrusted bytes.
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <vector>

namespace reprise::codec {

class ByteWriter {
public:
    explicit ByteWriter(std::vector<uint8_t>& out) : out_(out) {}
    void u8(uint8_t v) { out_.push_back(v); }
    void u16(uint16_t v) { put(v, 2); }
    void u32(uint32_t v) { put(v, 4); }
    void u64(uint64_t v) { put(v, 8); }
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
    void varint(uint64_t v) {
        while (v >= 0x80) {
            out_.push_back(uint8_t(v | 0x80));
            v >>= 7;
        }
        out_.push_back(uint8_t(v));
    }
    void bytes(std::span<const uint8_t> b) { out_.insert(out_.end(), b.begin(), b.end()); }
    std::size_t size() const { return out_.size(); }

private:
    void put(uint64_t v, int n) {
        for (int i = 0; i < n; ++i) out_.push_back(uint8_t(v >> (8 * i)));
    }
    std::vector<uint8_t>& out_;
};

// Every read checks what remains; after the first failure all reads return 0 and ok() is false.
class ByteReader {
public:
    ByteReader(std::span<const uint8_t> in, std::string what) : in_(in), what_(std::move(what)) {}
    uint8_t u8() { return uint8_t(get(1)); }
    uint16_t u16() { return uint16_t(get(2)); }
    uint32_t u32() { return uint32_t(get(4)); }
    uint64_t u64() { return get(8); }
    float f32() {
        uint32_t u = u32();
        float v;
        std::memcpy(&v, &u, 4);
        return v;
    }
    double f64() {
        uint64_t u = u64();
        double v;
        std::memcpy(&v, &u, 8);
        return v;
    }
    uint64_t varint() {
        uint64_t v = 0;
        for (int shift = 0; shift < 64; shift += 7) {
            uint8_t b = u8();
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
    std::size_t remaining() const { return in_.size() - pos_; }
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
            fail("truncated (needs " + std::to_string(n) + " bytes, " +
                 std::to_string(remaining()) + " left)");
            return 0;
        }
        uint64_t v = 0;
        for (int i = 0; i < n; ++i) v |= uint64_t(in_[pos_ + i]) << (8 * i);
        pos_ += n;
        return v;
    }
    std::span<const uint8_t> in_;
    std::size_t pos_ = 0;
    bool ok_ = true;
    std::string what_, error_;
};

}  // namespace reprise::codec
