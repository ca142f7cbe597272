// Inter prediction: every pixel of each plane fetched from the reference picture at p + motion
// with a Catmull-Rom filter in 1/64-pixel integer arithmetic (bit-exact on every machine).
// Whole-pixel motion copies exactly; positions outside the plane clamp to its edge. Then pixels
// the reference did not see (by depth) continue the surface beside them along their row.
#include <algorithm>
#include <array>
#include <cmath>

#include "internal.hpp"
#include "kernels.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::codec {

namespace {

constexpr int kPhases = 64;

struct WeightTable {
    int32_t w[kPhases][4];
    WeightTable() {
        for (int p = 0; p < kPhases; ++p) {
            const double f = double(p) / kPhases, f2 = f * f, f3 = f2 * f;
            const double c[4] = {0.5 * (-f3 + 2 * f2 - f), 0.5 * (3 * f3 - 5 * f2 + 2),
                                 0.5 * (-3 * f3 + 4 * f2 + f), 0.5 * (f3 - f2)};
            int sum = 0, largest = 0;
            for (int i = 0; i < 4; ++i) {
                w[p][i] = int32_t(std::lround(c[i] * 128.0));
                sum += w[p][i];
                if (w[p][i] > w[p][largest]) largest = i;
            }
            w[p][largest] += 128 - sum;
        }
    }
};

// Sample position in 1/64 of the plane's pixels, of a pixel centre moved by m (plane pixels).
inline int32_t fixed_position(float centre, float m, int size) {
    float q = (centre + m - 0.5f) * float(kPhases);
    q = std::clamp(q, -4.0f * kPhases, float(size + 4) * kPhases);
    const int32_t t = int32_t(q);  // floor without a library call (|q| < 2^21)
    return t - int32_t(q < float(t));
}

inline int sample(const PredictRow& r, int32_t qx, int32_t qy) {
    const int ix = qx >> 6, iy = qy >> 6;
    const auto& wx = catmull_rom_weights()[qx & 63];
    const auto& wy = catmull_rom_weights()[qy & 63];
    const int w = r.width, h = r.height;
    const int16_t* ref = r.reference;
    if ((qx & 63) == 0 && (qy & 63) == 0)
        return ref[std::size_t(std::clamp(iy, 0, h - 1)) * w + std::clamp(ix, 0, w - 1)];
    int32_t sum = 0;
    if (ix >= 1 && iy >= 1 && ix + 2 < w && iy + 2 < h) {  // the whole 4x4 window inside
        const int16_t* row = ref + std::size_t(iy - 1) * w + (ix - 1);
        for (int j = 0; j < 4; ++j, row += w)
            sum += wy[j] * (wx[0] * row[0] + wx[1] * row[1] + wx[2] * row[2] + wx[3] * row[3]);
        return std::clamp((sum + (1 << 13)) >> 14, r.lo, r.hi);
    }
    for (int j = 0; j < 4; ++j) {
        const int16_t* row = ref + std::size_t(std::clamp(iy - 1 + j, 0, h - 1)) * w;
        int32_t line = 0;
        for (int i = 0; i < 4; ++i) line += wx[i] * row[std::clamp(ix - 1 + i, 0, w - 1)];
        sum += wy[j] * line;
    }
    return std::clamp((sum + (1 << 13)) >> 14, r.lo, r.hi);
}

inline glm::vec2 usable(glm::vec2 m) {
    return std::isfinite(m.x) && std::isfinite(m.y) ? m : glm::vec2(0.0f);
}

// The reference saw pixel p where its depth at the landing p + m (nearest pixel) is within 4 % of
// p's own; a pixel off the reference's edge counts as seen (the prediction clamps to that edge).
inline bool seen(float depth, float landing) {
    return !(landing * 1.04f < depth || depth * 1.04f < landing);
}

inline bool same_surface(float a, float b) { return a == b || std::abs(a - b) <= 0.05f * a; }

}  // namespace

const int32_t (&catmull_rom_weights())[64][4] {
    static const WeightTable table;
    return table.w;
}

const uint32_t (&catmull_rom_packed())[64] {
    struct Packed {
        uint32_t words[kPhases] = {};
        Packed() {
            for (int p = 0; p < kPhases; ++p)
                for (int i = 0; i < 4; ++i) {
                    const int32_t biased = catmull_rom_weights()[p][i] + kPackedWeightBias;
                    REPRISE_ASSERT(biased >= 0 && biased < 256);
                    words[p] |= uint32_t(biased) << (8 * i);
                }
        }
    };
    static const Packed table;
    return table.words;
}

const uint32_t (&catmull_rom_pairs())[2][64] {
    struct Pairs {
        uint32_t words[2][kPhases] = {};
        Pairs() {
            for (int p = 0; p < kPhases; ++p)
                for (int k = 0; k < 2; ++k)
                    words[k][p] = uint32_t(uint16_t(catmull_rom_weights()[p][2 * k])) |
                                  uint32_t(uint16_t(catmull_rom_weights()[p][2 * k + 1])) << 16;
        }
    };
    static const Pairs table;
    return table.words;
}

void predict_row_reference(const PredictRow& r, int x_begin, int x_end) {
    const int last = r.motion_width - 1;
    const float cy = float(r.y) + 0.5f;
    for (int x = x_begin; x < x_end; ++x) {
        glm::vec2 m;
        if (!r.subsampled) {
            m = usable(r.motion0[std::min(x, last)]);
        } else {  // mean of the 2x2 luma motions, in chroma pixels
            const int a = std::min(2 * x, last), b = std::min(2 * x + 1, last);
            m = (usable(r.motion0[a]) + usable(r.motion0[b]) + usable(r.motion1[a]) +
                 usable(r.motion1[b])) *
                0.125f;
        }
        r.out[x] = int16_t(sample(r, fixed_position(float(x) + 0.5f, m.x, r.width),
                                  fixed_position(cy, m.y, r.height)));
    }
}

std::size_t reveal_row_reference(const RevealRow& r, int x_begin, int x_end) {
    const int w = r.width, h = r.height, y = r.y;
    std::size_t count = 0;
    for (int x = x_begin; x < x_end; ++x) {
        // Inside the picture (never with NaN or infinite motion), truncation is the floor.
        const glm::vec2 m = r.motion[x];
        const float fx = float(x) + 0.5f + m.x, fy = float(y) + 0.5f + m.y;
        const bool inside = fx >= 0.0f && fy >= 0.0f && fx < float(w) && fy < float(h);
        r.out[x] = inside &&
                   !seen(r.depth[x], r.reference_depth[std::size_t(int(fy)) * r.reference_stride +
                                                       std::size_t(int(fx))]);
        count += r.out[x];
    }
    return count;
}

namespace {

// Marks row y's revealed luma pixels; returns how many.
std::size_t mark_revealed(const Reveal& r, ImageView<const glm::vec2> motion, int y) {
    return reveal_row({.depth = r.depth.row(y),
                       .motion = motion.row(y),
                       .reference_depth = r.reference_depth.data,
                       .width = r.depth.width,
                       .height = r.depth.height,
                       .y = y,
                       .reference_stride = int(r.reference_depth.stride),
                       .out = r.revealed.row(y)});
}

// Row y of a plane with subsampling shift s: its revealed samples take their sources'.
void fill_row(const Reveal& r, int s, int y, int16_t* row) {
    const int w = r.depth.width;
    const int ly = y << s;
    const uint8_t* revealed = r.revealed.row(ly);
    const float* d = r.depth.row(ly);
    const int pw = (w + (1 << s) - 1) >> s, reach = 32 >> s;
    auto source = [&](int x, int dx) {
        const int sx = x + dx;
        if (sx < 0 || sx >= pw) return false;
        return !revealed[sx << s] && same_surface(d[x << s], d[sx << s]);
    };
    for (int x = 0; x < pw; ++x) {
        if (!revealed[x << s]) continue;
        for (int dist = 1; dist <= reach; ++dist) {
            const int dir = source(x, -dist) ? -1 : source(x, dist) ? 1 : 0;
            if (dir == 0) continue;
            // Mirrored about the strip's edge where that pixel qualifies too: the surface's
            // texture continues instead of one pixel smeared.
            const int mirrored = dir * (2 * dist - 1);
            row[x] = row[x + (source(x, mirrored) ? mirrored : dir * dist)];
            break;
        }
    }
}

bool picture_sized(const Reveal* r, const SequenceParams& sp) {
    return r && r->depth.width == sp.width && r->depth.height == sp.height &&
           r->reference_depth.width == sp.width && r->reference_depth.height == sp.height &&
           r->revealed.width == sp.width && r->revealed.height == sp.height;
}

}  // namespace

std::size_t predict_planes(const Planes& ref, const SequenceParams& sp,
                           ImageView<const glm::vec2> motion, Planes& out, const Reveal* reveal) {
    const int w = sp.width, h = sp.height;
    for (int k = 0; k < 3; ++k) ensure_size(out.p[k], sp.plane_width(k), sp.plane_height(k));
    const int rows = sp.plane_height(0);
    const int chroma_rows = sp.plane_height(1);
    if (!picture_sized(reveal, sp)) reveal = nullptr;
    std::vector<std::size_t> revealed(std::size_t(rows), 0);
    // One pass over the luma rows; each worker also makes the chroma rows its luma rows cover,
    // after them, so that the revealed pixels of those luma rows are marked.
    const int s = sp.shift(1);
    parallel_for(0, rows >> s, [&](int r0, int r1) {
        for (int r = r0; r < r1; ++r)
            for (int k = 0; k < 3; ++k) {
                if (k > 0 && r >= chroma_rows) break;
                const int sub = sp.shift(k);
                for (int y = sub ? r : r << s; y < (sub ? r + 1 : (r + 1) << s); ++y) {
                    const int my = std::min(y << sub, h - 1);
                    const PredictRow row{
                        .reference = ref.p[k].data(),
                        .width = ref.p[k].width(),
                        .height = ref.p[k].height(),
                        .y = y,
                        .motion0 = motion.row(my),
                        .motion1 = motion.row(std::min((y << sub) + 1, h - 1)),
                        .motion_width = w,
                        .subsampled = sub != 0,
                        .lo = k ? -255 : 0,
                        .hi = 255,
                        .out = out.p[k].data() + std::size_t(y) * out.p[k].width(),
                    };
                    predict_row(row);
                    if (!reveal || (y << sub) >= h) continue;
                    if (k == 0) revealed[std::size_t(y)] = mark_revealed(*reveal, motion, y);
                    if (revealed[std::size_t(y << sub)]) fill_row(*reveal, sub, y, row.out);
                }
            }
    });
    std::size_t total = 0;
    for (std::size_t c : revealed) total += c;
    return total;
}

std::size_t fill_revealed(const SequenceParams& sp, ImageView<const glm::vec2> motion,
                          const Reveal& reveal, Planes& predicted) {
    if (!picture_sized(&reveal, sp)) return 0;
    std::size_t total = 0;
    for (int y = 0; y < sp.height; ++y) {
        const std::size_t count = mark_revealed(reveal, motion, y);
        total += count;
        if (!count) continue;
        for (int k = 0; k < 3; ++k) {
            const int s = sp.shift(k);
            if (y % (1 << s) == 0)
                fill_row(reveal, s, y >> s,
                         predicted.p[k].data() + std::size_t(y >> s) * predicted.p[k].width());
        }
    }
    return total;
}

}  // namespace reprise::codec
