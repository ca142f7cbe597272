#pragma once
// Adaptive binary range coder (LZMA-style carry propagation, 12-bit probabilities) and the
// integer binarisations built on it. The encoder leaves out the leading zero byte and the
// trailing zero bytes of its last value; the decoder never reads outside its input: past the end
// it sees zero bytes and counts them (an honest slice: at most 4), so a truncated or hostile
// slice decodes to garbage values that the caller bounds, never to undefined behaviour.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace reprise::codec {

inline constexpr int kProbBits = 12;

// The probability of a 0 as the mean of two estimates in 1/32768, one moving 1/8 and one 1/64
// (version 20; 1/32 before) of the way to each bit seen; a model's first bits move them further
// (1/2, 1/4, ...), as a model starts at 1/2 in every slice of a key frame (an inter frame's carry
// on from its reference's, slices.hpp) and many see only a few hundred bits.
struct BitModel {
    uint16_t fast = 1 << 14, slow = 1 << 14;
    uint8_t seen = 0;                                            // bits seen, up to 5
    uint32_t p() const { return (uint32_t(fast) + slow) >> 4; }  // in 1/4096, 4..4091
    void update(int b) {
        const int f = std::min(int(seen) + 1, 3), s = std::min(int(seen) + 1, 6);
        if (seen < 5) ++seen;
        if (!b) {
            fast += ((1 << 15) - fast) >> f;
            slow += ((1 << 15) - slow) >> s;
        } else {
            fast -= fast >> f;
            slow -= slow >> s;
        }
    }
};

// -log2 of a probability of p / 4096: the ideal length of a coded bit.
inline const std::array<float, 4097> kBitLength = [] {
    std::array<float, 4097> t{};
    for (int p = 1; p <= 4096; ++p) t[std::size_t(p)] = float(-std::log2(double(p) / 4096.0));
    t[0] = t[1];
    return t;
}();

class RangeEncoder {
public:
    explicit RangeEncoder(std::vector<uint8_t>& out) : out_(out), start_(out.size()) {}

    // From here on, the ideal length of each bit coded (bits) is added to *t (null: none).
    void tally_into(double* t) { tally_ = t; }

    void bit(BitModel& m, int b) {
        if (tally_) *tally_ += kBitLength[b ? 4096 - m.p() : m.p()];
        const uint32_t bound = (range_ >> kProbBits) * m.p();
        if (!b) {
            range_ = bound;
        } else {
            low_ += bound;
            range_ -= bound;
        }
        m.update(b);
        normalize();
    }
    void bypass(int b) {
        if (tally_) *tally_ += 1.0;
        range_ >>= 1;
        if (b) low_ += range_;
        normalize();
    }
    void bypass_bits(uint32_t v, int n) {
        for (int i = n - 1; i >= 0; --i) bypass((v >> i) & 1);
    }
    // Ends the slice on the value in [low, low + range) with the most trailing zero bits and
    // leaves its trailing zero bytes out (at least 3, as range >= 2^24): the decoder reads zeros
    // past the end.
    void finish() {
        for (int k = 32; k >= 0; --k) {
            const uint64_t mask = (uint64_t(1) << k) - 1, v = (low_ + mask) & ~mask;
            if (v < low_ + range_) {
                low_ = v;
                break;
            }
        }
        const uint32_t last = uint32_t(low_);
        for (int i = 0; i < 5; ++i) shift_low();
        for (int i = 0; i < 4 && !(last >> (8 * i) & 0xFF) && out_.size() > start_; ++i)
            out_.pop_back();
    }

private:
    void normalize() {
        while (range_ < (1u << 24)) {
            range_ <<= 8;
            shift_low();
        }
    }
    void shift_low() {
        if (uint32_t(low_) < 0xFF000000u || (low_ >> 32) != 0) {
            const uint8_t carry = uint8_t(low_ >> 32);
            uint8_t temp = cache_;
            do {
                if (!first_) out_.push_back(uint8_t(temp + carry));  // the first is always 0
                first_ = false;
                temp = 0xFF;
            } while (--cache_size_ != 0);
            cache_ = uint8_t(low_ >> 24);
        }
        ++cache_size_;
        low_ = (low_ & 0x00FFFFFFu) << 8;
    }

    std::vector<uint8_t>& out_;
    std::size_t start_;
    bool first_ = true;
    uint64_t low_ = 0;
    uint32_t range_ = 0xFFFFFFFFu;
    uint8_t cache_ = 0;
    uint64_t cache_size_ = 1;
    double* tally_ = nullptr;
};

class RangeDecoder {
public:
    explicit RangeDecoder(std::span<const uint8_t> in) : in_(in) {
        for (int i = 0; i < 4; ++i) code_ = (code_ << 8) | next();
    }

    int bit(BitModel& m) {
        const uint32_t bound = (range_ >> kProbBits) * m.p();
        int b;
        if (code_ < bound) {
            range_ = bound;
            b = 0;
        } else {
            code_ -= bound;
            range_ -= bound;
            b = 1;
        }
        m.update(b);
        normalize();
        return b;
    }
    int bypass() {
        range_ >>= 1;
        int b = 0;
        if (code_ >= range_) {
            code_ -= range_;
            b = 1;
        }
        normalize();
        return b;
    }
    uint32_t bypass_bits(int n) {
        uint32_t v = 0;
        for (int i = 0; i < n; ++i) v = (v << 1) | uint32_t(bypass());
        return v;
    }
    // Bytes read beyond the input (an honest slice: at most 4, its trailing zeros).
    std::size_t overrun() const { return overrun_; }

private:
    uint8_t next() {
        if (pos_ < in_.size()) return in_[pos_++];
        ++overrun_;
        return 0;
    }
    void normalize() {
        while (range_ < (1u << 24)) {
            range_ <<= 8;
            code_ = (code_ << 8) | next();
        }
    }

    std::span<const uint8_t> in_;
    std::size_t pos_ = 0;
    std::size_t overrun_ = 0;
    uint32_t code_ = 0;
    uint32_t range_ = 0xFFFFFFFFu;
};

// Unsigned integers as an Exp-Golomb code: the bit length of v + 1 in unary, each unary bin with
// its own model (the last one shared by the rest), then the bits below the leading one in bypass.
template <int N>
struct UintModel {
    BitModel prefix[N];
};

template <int N>
void encode_uint(RangeEncoder& rc, UintModel<N>& m, uint32_t v) {
    const uint64_t x = uint64_t(v) + 1;
    int n = 0;
    while ((x >> (n + 1)) != 0) ++n;
    for (int i = 0; i < n; ++i) rc.bit(m.prefix[i < N ? i : N - 1], 1);
    rc.bit(m.prefix[n < N ? n : N - 1], 0);
    for (int i = n - 1; i >= 0; --i) rc.bypass(int((x >> i) & 1));
}

// Returns false when the prefix is longer than 32 bins (no encoder writes that).
template <int N>
bool decode_uint(RangeDecoder& rc, UintModel<N>& m, uint32_t& v) {
    int n = 0;
    while (rc.bit(m.prefix[n < N ? n : N - 1])) {
        if (++n > 32) return false;
    }
    uint64_t x = 1;
    for (int i = 0; i < n; ++i) x = (x << 1) | uint64_t(rc.bypass());
    if (x - 1 > 0xFFFFFFFFull) return false;
    v = uint32_t(x - 1);
    return true;
}

// Signed: zero flag, sign, magnitude - 1.
template <int N>
struct IntModel {
    BitModel zero;
    BitModel sign;
    UintModel<N> magnitude;
};

// The part after the zero flag, for callers that code something between (v != 0).
template <int N>
void encode_nonzero_int(RangeEncoder& rc, IntModel<N>& m, int64_t v) {
    rc.bit(m.sign, v < 0);
    const uint64_t a = v < 0 ? uint64_t(-v) : uint64_t(v);
    encode_uint(rc, m.magnitude, uint32_t(a - 1));
}

template <int N>
bool decode_nonzero_int(RangeDecoder& rc, IntModel<N>& m, int64_t& v) {
    const int negative = rc.bit(m.sign);
    uint32_t a = 0;
    if (!decode_uint(rc, m.magnitude, a)) return false;
    v = negative ? -(int64_t(a) + 1) : int64_t(a) + 1;
    return true;
}

template <int N>
void encode_int(RangeEncoder& rc, IntModel<N>& m, int64_t v) {
    rc.bit(m.zero, v != 0);
    if (v != 0) encode_nonzero_int(rc, m, v);
}

template <int N>
bool decode_int(RangeDecoder& rc, IntModel<N>& m, int64_t& v) {
    v = 0;
    return !rc.bit(m.zero) || decode_nonzero_int(rc, m, v);
}

}  // namespace reprise::codec
