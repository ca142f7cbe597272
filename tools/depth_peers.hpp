#pragma once
// Peers of reprise's depth coding (issue 8 §2): zstd on the raw float depth, and an RVL-style
// coder (Wilson 2017, "Fast lossless depth image compression": run lengths of zeros, then the
// differences between successive nonzero values, zigzag-mapped and written as variable-length
// nibbles of 3 data bits and a continuation bit).
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "reprise/core/status.hpp"

namespace reprise::cli {

// zstd at `level` (3 = `zstd -3`) of the floats' bytes as they are in memory.
void zstd_compress_depth(std::span<const float> depth, int level, std::vector<uint8_t>& out);
Status zstd_decompress_depth(std::span<const uint8_t> in, std::size_t count,
                             std::vector<float>& out);

enum class RvlMode : uint8_t {
    // Lossless on every bit pattern: the float bits shifted so that +inf (background) is 0; a
    // zero run is a run of background, deltas are taken between bit patterns (positive floats
    // order like their bits, so smooth depth makes small deltas).
    FloatBits = 0,
    // 16 bits linear in 1/z between 1/far (1) and 1/near (65535), 0 = background or outside:
    // lossy, like the 16-bit sensor depth RVL was made for.
    Inverse16 = 1,
};

struct RvlOptions {
    RvlMode mode = RvlMode::FloatBits;
    float near = 0.1f, far = 1000.0f;  // Inverse16 only
};

void rvl_encode(std::span<const float> depth, const RvlOptions& options, std::vector<uint8_t>& out);
// `count` values; an input that ends early, runs past `count` or leaves bytes over is an error.
Status rvl_decode(std::span<const uint8_t> in, std::size_t count, const RvlOptions& options,
                  std::vector<float>& out);

}  // namespace reprise::cli
