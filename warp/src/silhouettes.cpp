#include "reprise/warp/silhouettes.hpp"

#include <atomic>

#include "reprise/core/parallel.hpp"

namespace reprise::warp {

void widened_pixel(const GBufferView& f, int x, int y, float& depth, glm::vec2& motion) {
    // widen_silhouettes' rule for one pixel (its row loop keeps the rule inline: a shared helper
    // made it 1.6x slower).
    const int w = f.width(), h = f.height();
    const float z = f.depth(x, y);
    float nearest = z * kSilhouetteKeep;
    int nx = x, ny = y;
    auto consider = [&](int cx, int cy) {
        const float candidate = f.depth(cx, cy);
        if (candidate > 0.0f && candidate < nearest) {
            nearest = candidate;
            nx = cx;
            ny = cy;
        }
    };
    if (z > 0.0f) {
        if (x > 0) consider(x - 1, y);
        if (x + 1 < w) consider(x + 1, y);
        if (y > 0) consider(x, y - 1);
        if (y + 1 < h) consider(x, y + 1);
    }
    depth = nx == x && ny == y ? z : nearest;
    motion = f.motion(nx, ny);
}

GBufferView widen_silhouettes(const GBufferView& f, Image<float>& depth, Image<glm::vec2>& motion,
                              std::size_t* changed) {
    if (f.depth.empty()) return f;
    const int w = f.width(), h = f.height();
    const bool moves = !f.motion.empty();
    depth.resize(w, h);
    if (moves) motion.resize(w, h);
    std::atomic<std::size_t> total{0};
    parallel_for(0, h, [&](int y0, int y1) {
        std::size_t count = 0;
        for (int y = y0; y < y1; ++y) {
            const float* z = f.depth.row(y);
            const float* up = f.depth.row(y > 0 ? y - 1 : y);
            const float* down = f.depth.row(y + 1 < h ? y + 1 : y);
            const glm::vec2* m = moves ? f.motion.row(y) : nullptr;
            float* z_out = depth.view().row(y);
            glm::vec2* m_out = moves ? motion.view().row(y) : nullptr;
            for (int x = 0; x < w; ++x) {
                z_out[x] = z[x];
                if (moves) m_out[x] = m[x];
                // Nearer than kSilhouetteKeep * z, and a real depth (NaN and <= 0 fail both tests).
                float nearest = z[x] * kSilhouetteKeep;
                int nx = -1, ny = 0;
                auto consider = [&](float candidate, int cx, int cy) {
                    if (candidate > 0.0f && candidate < nearest) {
                        nearest = candidate;
                        nx = cx;
                        ny = cy;
                    }
                };
                if (!(z[x] > 0.0f)) continue;
                if (x > 0) consider(z[x - 1], x - 1, y);
                if (x + 1 < w) consider(z[x + 1], x + 1, y);
                if (y > 0) consider(up[x], x, y - 1);
                if (y + 1 < h) consider(down[x], x, y + 1);
                if (nx < 0) continue;
                z_out[x] = nearest;
                if (moves) m_out[x] = f.motion(nx, ny);
                ++count;
            }
        }
        total += count;
    });
    if (changed) *changed = total.load();
    GBufferView widened = f;
    widened.depth = std::as_const(depth).view();
    if (moves) widened.motion = std::as_const(motion).view();
    return widened;
}

}  // namespace reprise::warp
