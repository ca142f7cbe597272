#include "reprise/warp/shot_change.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "reprise/core/frame.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::warp {

namespace {

struct DisplayTable {
    float values[kDisplayTableSize + 1];
    DisplayTable() {
        for (int i = 0; i <= kDisplayTableSize; ++i)
            values[i] = linear_to_srgb(float(i) / kDisplayTableSize);
    }
};

const DisplayTable& table() {
    static const DisplayTable t;
    return t;
}

// linear_to_srgb from the table with linear interpolation (within 4e-4 of it; exact on the
// linear segment's grid points).
float display(const float* values, float linear) {
    const float c = linear >= 0.0f ? std::min(linear, 1.0f) * kDisplayTableSize : 0.0f;  // NaN: 0
    const int i = std::min(int(c), kDisplayTableSize - 1);
    const float t = c - float(i);
    const float step = values[i + 1] - values[i];
    const float offset = step * t;  // apart: no multiply-add, as the GPU computes it
    return values[i] + offset;
}

}  // namespace

const float* display_table() { return table().values; }

uint32_t display_difference(const glm::vec4& a, const glm::vec4& b) {
    const float* values = table().values;
    uint32_t sum = 0;
    for (int k = 0; k < 3; ++k) {
        const float d = std::abs(display(values, a[k]) - display(values, b[k]));
        sum += uint32_t(std::floor(d * 1048576.0f + 0.5f));
    }
    return sum;
}

bool shot_change_decision(const ReprojectCounts& counts, uint64_t difference, int width, int height,
                          float cut_misses, float cut_color) {
    const double pixels = double((width + kShotChangeStep - 1) / kShotChangeStep) *
                          ((height + kShotChangeStep - 1) / kShotChangeStep);
    const double lost = double(counts.behind + counts.occluded + counts.other_id + counts.invalid);
    if (lost > cut_misses * pixels) return true;
    if (counts.hits == 0) return double(counts.offscreen) > cut_misses * pixels;
    return double(difference) / 1048576.0 / (3.0 * double(counts.hits)) > cut_color;
}

ShotChange shot_change(const GBufferView& frame, const GBufferView& previous, float cut_misses,
                       float cut_color, ShotChangeScratch& scratch) {
    ShotChange result;
    const int w = frame.width(), h = frame.height();
    if (frame.depth.empty() || frame.motion.empty() || previous.depth.empty()) return result;
    scratch.reprojected.resize(w, h);
    scratch.hit.resize(w, h);
    result.counts =
        reproject(frame, previous, payload_of(previous.color),
                  payload_of(scratch.reprojected.view()), scratch.hit.view(),
                  {.depth_tolerance = kShotChangeDepthTolerance, .step = kShotChangeStep});
    std::atomic<uint64_t> difference{0};
    const int rows = (h + kShotChangeStep - 1) / kShotChangeStep;
    parallel_for(
        0, rows,
        [&](int r0, int r1) {
            uint64_t local = 0;
            for (int y = r0 * kShotChangeStep; y < std::min(r1 * kShotChangeStep, h);
                 y += kShotChangeStep)
                for (int x = 0; x < w; x += kShotChangeStep)
                    if (scratch.hit(x, y))
                        local += display_difference(frame.color(x, y), scratch.reprojected(x, y));
            difference += local;
        },
        8);
    result.difference = difference;
    result.cut =
        shot_change_decision(result.counts, result.difference, w, h, cut_misses, cut_color);
    return result;
}

}  // namespace reprise::warp
