// In-loop deblocking: after a picture's slices are decoded, the 8x8 block edges next to a coded
// block (intra, or with a residual) are smoothed where the step across them is small enough to be
// a coding artefact rather than an image edge. Encoder and decoder filter alike, so references
// carry it. Edges between two uncoded inter blocks are left alone: their pixels are the
// reprojected reference, and filtering them every frame would blur it away.
#include <algorithm>
#include <cstdlib>

#include "internal.hpp"
#include "reprise/core/parallel.hpp"
#include "transform.hpp"

namespace reprise::codec {

namespace {

struct Thresholds {
    int alpha, beta, tc;  // step across the edge, steps beside it, largest correction
};

// From the quantiser step s = 2^((qp - 4) / 6) levels (s16 = 16 s): alpha = 1.5 s + 1,
// beta = 0.3 s + 1, tc = 0.15 s + 1; doubled for chroma (Co and Cg span twice the range).
Thresholds thresholds(int qp, bool chroma) {
    const int s16 = quant_scale(qp) / 32;
    Thresholds t{(3 * s16) / 32 + 1, (3 * s16) / 160 + 1, (3 * s16) / 320 + 1};
    if (chroma) t = {2 * t.alpha, 2 * t.beta, 2 * t.tc};
    return t;
}

inline void filter(int16_t& p1, int16_t& p0, int16_t& q0, int16_t& q1, const Thresholds& t,
                   int lo) {
    if (std::abs(p0 - q0) >= t.alpha || std::abs(p1 - p0) >= t.beta || std::abs(q1 - q0) >= t.beta)
        return;
    const int d = std::clamp((4 * (q0 - p0) + (p1 - q1) + 4) >> 3, -t.tc, t.tc);
    p0 = int16_t(std::clamp(p0 + d, lo, 255));
    q0 = int16_t(std::clamp(q0 - d, lo, 255));
    (void)p1;
    (void)q1;
}

}  // namespace

void deblock(Planes& planes, const std::vector<uint8_t> (&coded)[3], int qp) {
    for (int k = 0; k < 3; ++k) {
        Image<int16_t>& p = planes.p[k];
        const int w = p.width(), h = p.height(), bw = w / 8;
        const Thresholds t = thresholds(qp, k > 0);
        const int lo = k ? -255 : 0;
        const uint8_t* c = coded[k].data();
        // Vertical edges, row by row.
        parallel_for(0, h, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                int16_t* row = p.data() + std::size_t(y) * w;
                const uint8_t* cr = c + std::size_t(y / 8) * bw;
                for (int b = 1; b < bw; ++b)
                    if (cr[b - 1] | cr[b])
                        filter(row[8 * b - 2], row[8 * b - 1], row[8 * b], row[8 * b + 1], t, lo);
            }
        });
        // Horizontal edges, one block row boundary per task.
        parallel_for(
            1, h / 8,
            [&](int e0, int e1) {
                for (int e = e0; e < e1; ++e) {
                    int16_t* r0 = p.data() + std::size_t(8 * e - 2) * w;
                    int16_t* r1 = r0 + w;
                    int16_t* r2 = r1 + w;
                    int16_t* r3 = r2 + w;
                    const uint8_t* above = c + std::size_t(e - 1) * bw;
                    const uint8_t* below = above + bw;
                    for (int x = 0; x < w; ++x)
                        if (above[x / 8] | below[x / 8]) filter(r0[x], r1[x], r2[x], r3[x], t, lo);
                }
            },
            1);
    }
}

}  // namespace reprise::codec
