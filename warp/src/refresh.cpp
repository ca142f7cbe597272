// Refresh policies (Nehab et al. 2007, §5): which cached pixels are recomputed this frame.
#include <cmath>

#include "reprise/warp/reproject.hpp"

namespace reprise::warp {

namespace {

uint64_t mix(uint64_t v) {  // splitmix64 finaliser
    v ^= v >> 30;
    v *= 0xbf58476d1ce4e5b9ull;
    v ^= v >> 27;
    v *= 0x94d049bb133111ebull;
    return v ^ (v >> 31);
}

// rows x cols = n, with tiles as close to square as the divisors of n allow.
void tile_grid(int n, int width, int height, int64_t& rows, int64_t& cols) {
    rows = 1;
    cols = n;
    double best = INFINITY;
    for (int64_t r = 1; r * r <= n; ++r) {
        if (n % r) continue;
        for (int64_t candidate : {r, int64_t(n) / r}) {
            double aspect =
                (double(width) / double(n / candidate)) / (double(height) / double(candidate));
            double badness = std::abs(std::log(aspect));
            if (badness < best) {
                best = badness;
                rows = candidate;
                cols = n / candidate;
            }
        }
    }
}

}  // namespace

void refresh_mask(Refresh policy, int n, int64_t t, ImageView<uint8_t> mask, uint32_t seed) {
    REPRISE_ASSERT(n >= 1);
    const int64_t w = mask.width, h = mask.height;
    const int64_t now = ((t % n) + n) % n;
    auto due = [&](int64_t phase) { return uint8_t((now + phase) % n == 0); };
    switch (policy) {
        case Refresh::None:
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) mask(x, y) = 0;
            return;
        case Refresh::Tiled: {
            int64_t rows, cols;
            tile_grid(n, mask.width, mask.height, rows, cols);
            const int64_t row = now / cols, col = now % cols;
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) mask(x, y) = y * rows / h == row && x * cols / w == col;
            return;
        }
        case Refresh::Random2x2: {
            const int64_t blocks_per_row = (w + 1) / 2;
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    const int64_t block = (y / 2) * blocks_per_row + x / 2;
                    const uint64_t shift =
                        mix(uint64_t(block / n) ^ (uint64_t(seed) << 40)) % uint64_t(n);
                    mask(x, y) = due((block % n + int64_t(shift)) % n);
                }
            return;
        }
        case Refresh::Interleaved:
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) mask(x, y) = due((x + y * w) % n);
            return;
    }
}

}  // namespace reprise::warp
