#include "depth_peers.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <string>

#include <zstd.h>

namespace reprise::cli {

namespace {

constexpr uint32_t kInfBits = 0x7f800000u;

uint32_t to_code(float z, const RvlOptions& o) {
    if (o.mode == RvlMode::FloatBits) return std::bit_cast<uint32_t>(z) - kInfBits;
    if (!(z >= o.near && z <= o.far)) return 0;  // background, NaN, outside [near, far]
    const double t = (1.0 / z - 1.0 / o.far) / (1.0 / o.near - 1.0 / o.far);
    return 1 + uint32_t(std::lround(std::clamp(t, 0.0, 1.0) * 65534.0));
}

float from_code(uint32_t code, const RvlOptions& o) {
    if (o.mode == RvlMode::FloatBits) return std::bit_cast<float>(code + kInfBits);
    if (code == 0) return INFINITY;
    const double inv = 1.0 / o.far + double(code - 1) / 65534.0 * (1.0 / o.near - 1.0 / o.far);
    return float(1.0 / inv);
}

class NibbleWriter {
public:
    explicit NibbleWriter(std::vector<uint8_t>& out) : out_(out) {}
    void value(uint32_t v) {
        do {
            uint32_t nibble = v & 7u;
            v >>= 3;
            if (v) nibble |= 8u;
            put(nibble);
        } while (v);
    }
    void finish() {
        if (half_) out_.push_back(pending_);
    }

private:
    void put(uint32_t nibble) {
        if (!half_) {
            pending_ = uint8_t(nibble);
        } else {
            out_.push_back(uint8_t(pending_ | (nibble << 4)));
        }
        half_ = !half_;
    }
    std::vector<uint8_t>& out_;
    uint8_t pending_ = 0;
    bool half_ = false;
};

class NibbleReader {
public:
    explicit NibbleReader(std::span<const uint8_t> in) : in_(in) {}
    bool value(uint32_t& v) {
        v = 0;
        for (int shift = 0; shift < 33; shift += 3) {
            if (at_ >= 2 * in_.size()) return false;
            const uint32_t nibble = (in_[at_ / 2] >> (4 * (at_ & 1))) & 15u;
            ++at_;
            if (shift == 30 && (nibble & 7u) > 3u) return false;  // more than 32 bits
            v |= (nibble & 7u) << shift;
            if (!(nibble & 8u)) return true;
        }
        return false;
    }
    // Whole bytes used (a last half byte is padding).
    std::size_t bytes_used() const { return (at_ + 1) / 2; }

private:
    std::span<const uint8_t> in_;
    std::size_t at_ = 0;  // in nibbles
};

uint32_t zigzag(uint32_t delta) {
    const int32_t s = std::bit_cast<int32_t>(delta);
    return (uint32_t(s) << 1) ^ uint32_t(s >> 31);
}
uint32_t unzigzag(uint32_t z) { return (z >> 1) ^ (0u - (z & 1u)); }

}  // namespace

void zstd_compress_depth(std::span<const float> depth, int level, std::vector<uint8_t>& out) {
    out.resize(ZSTD_compressBound(depth.size_bytes()));
    const std::size_t size =
        ZSTD_compress(out.data(), out.size(), depth.data(), depth.size_bytes(), level);
    REPRISE_ASSERT(!ZSTD_isError(size));
    out.resize(size);
}

Status zstd_decompress_depth(std::span<const uint8_t> in, std::size_t count,
                             std::vector<float>& out) {
    out.resize(count);
    const std::size_t size =
        ZSTD_decompress(out.data(), count * sizeof(float), in.data(), in.size());
    if (ZSTD_isError(size))
        return Status::error(std::string("zstd depth: ") + ZSTD_getErrorName(size));
    if (size != count * sizeof(float))
        return Status::error("zstd depth: " + std::to_string(size) + " bytes instead of " +
                             std::to_string(count * sizeof(float)));
    return {};
}

void rvl_encode(std::span<const float> depth, const RvlOptions& options,
                std::vector<uint8_t>& out) {
    out.clear();
    NibbleWriter writer(out);
    uint32_t previous = 0;
    std::size_t i = 0;
    while (i < depth.size()) {
        std::size_t zeros = 0, nonzeros = 0;
        while (i + zeros < depth.size() && to_code(depth[i + zeros], options) == 0) ++zeros;
        const std::size_t start = i + zeros;
        while (start + nonzeros < depth.size() && to_code(depth[start + nonzeros], options) != 0)
            ++nonzeros;
        writer.value(uint32_t(zeros));
        writer.value(uint32_t(nonzeros));
        for (std::size_t k = start; k < start + nonzeros; ++k) {
            const uint32_t code = to_code(depth[k], options);
            writer.value(zigzag(code - previous));
            previous = code;
        }
        i = start + nonzeros;
    }
    writer.finish();
}

Status rvl_decode(std::span<const uint8_t> in, std::size_t count, const RvlOptions& options,
                  std::vector<float>& out) {
    out.resize(count);
    NibbleReader reader(in);
    uint32_t previous = 0;
    std::size_t i = 0;
    while (i < count) {
        uint32_t zeros = 0, nonzeros = 0;
        if (!reader.value(zeros) || !reader.value(nonzeros))
            return Status::error("rvl depth: the data ends inside a run length at value " +
                                 std::to_string(i));
        if (zeros > count - i || nonzeros > count - i - zeros)
            return Status::error("rvl depth: a run at value " + std::to_string(i) +
                                 " passes the end (" + std::to_string(count) + " values)");
        if (zeros + nonzeros == 0)
            return Status::error("rvl depth: empty run at value " + std::to_string(i));
        for (uint32_t k = 0; k < zeros; ++k) out[i++] = from_code(0, options);
        for (uint32_t k = 0; k < nonzeros; ++k) {
            uint32_t z = 0;
            if (!reader.value(z))
                return Status::error("rvl depth: the data ends at value " + std::to_string(i));
            previous += unzigzag(z);
            if (previous == 0 || (options.mode == RvlMode::Inverse16 && previous > 65535))
                return Status::error("rvl depth: bad value at " + std::to_string(i));
            out[i++] = from_code(previous, options);
        }
    }
    if (reader.bytes_used() != in.size())
        return Status::error("rvl depth: " + std::to_string(in.size() - reader.bytes_used()) +
                             " bytes left over");
    return {};
}

}  // namespace reprise::cli
