// Amortized sampling (Nehab et al. 2007, §6): an exponential moving average along motion.
#include <algorithm>
#include <cfloat>
#include <cmath>

#include "reprise/core/parallel.hpp"
#include "reprise/warp/reproject.hpp"

namespace reprise::warp {

void accumulate(ConstPayload sample, ConstPayload reprojected_history, ImageView<const uint8_t> hit,
                float alpha, ImageView<const float> alpha_map, Payload out) {
    const int w = sample.width, h = sample.height, channels = sample.channels;
    const ConstPayload& history = reprojected_history;
    REPRISE_ASSERT(history.width == w && history.height == h && history.channels == channels);
    REPRISE_ASSERT(out.width == w && out.height == h && out.channels == channels);
    REPRISE_ASSERT(hit.empty() || (hit.width == w && hit.height == h));
    REPRISE_ASSERT(alpha_map.empty() || (alpha_map.width == w && alpha_map.height == h));
    const int grain = std::max(1, 8192 / std::max(1, w * channels));
    parallel_for(
        0, h,
        [&](int y_begin, int y_end) {
            for (int y = y_begin; y < y_end; ++y) {
                const float* s = sample.pixel(0, y);
                const float* f = history.pixel(0, y);
                float* o = out.pixel(0, y);
                const uint8_t* hits = hit.empty() ? nullptr : hit.row(y);
                const float* alphas = alpha_map.empty() ? nullptr : alpha_map.row(y);
                for (int x = 0; x < w; ++x, s += channels, f += channels, o += channels) {
                    float a = alphas ? alphas[x] : alpha;
                    a = a < 0.0f ? 0.0f : (a <= 1.0f ? a : 1.0f);  // NaN -> 1
                    const bool restart = (hits && !hits[x]) || a == 1.0f;
                    for (int c = 0; c < channels; ++c) {
                        const float previous = f[c], now = s[c];
                        // h + a (s - h) keeps a constant signal exactly constant for any a.
                        float v = restart || !std::isfinite(previous)
                                      ? now
                                      : previous + a * (now - previous);
                        if (std::abs(v) < FLT_MIN) v = 0.0f;
                        o[c] = v;
                    }
                }
            }
        },
        grain);
}

}  // namespace reprise::warp
