// Colour residuals per 16x16 macroblock: inter prediction (reprojected reference) or intra
// prediction (DC / vertical / horizontal / smooth from decoded neighbours in the same slice),
// 8x8 integer DCT, dead-zone quantisation, context-coded levels. Inter blocks whose prediction
// error stays within the skip threshold are not coded at all.
#include <algorithm>
#include <cstdlib>

#include "internal.hpp"
#include "kernels.hpp"
#include "slices.hpp"
#include "transform.hpp"

namespace reprise::codec {

namespace {

constexpr uint8_t kAllSkipped = 1;
// Quantiser rounding offsets in 16ths of a step (encoder-only): intra 3/8 (best of 1/4..1/2 by
// BD-rate on stroll, pan, courtyard and mirror: -0.6 to -2.2 % against 5/16), inter 1/8.
constexpr int kIntraRounding = 6, kInterRounding = 2;
constexpr int kModes = 4;  // intra: DC, vertical, horizontal, smooth
constexpr int32_t kMaxLevel = 1 << 16;

// Significance contexts: the first 16 scan positions each their own, then groups of 4.
constexpr int kSignificanceClasses = 28;
inline int significance_class(int i) { return i < 16 ? i : 16 + (i - 16) / 4; }

struct Models {
    BitModel mb_skip[3];
    BitModel mb_intra[3];
    BitModel mode[2][25][4];  // [chroma][left and above blocks' modes + 1, 0: none][node]
    BitModel cbf[4][6];       // [type][left + above have levels, + 3: an earlier block of the
                              // macroblock has (chroma)]
    BitModel last[4][64];     // [type][node of the 6-bit binary tree]
    BitModel significant[4][kSignificanceClasses][2];  // [..][the next scan position has a level]
    BitModel greater1[4][3][4];     // [type][position class][levels so far: any > 1, else 0-2 ones]
    UintModel<14> remaining[4][3];  // [type][position class]
};

// The greater-than-one context of the next level from what the block's levels so far (coded from
// the last one down) were.
inline int greater1_state(int ones, bool any_greater) {
    return any_greater ? 0 : 1 + std::min(ones, 2);
}

// Block type for contexts: luma/chroma x intra/inter.
inline int block_type(int plane, bool intra) { return (plane ? 2 : 0) + (intra ? 0 : 1); }

struct Geometry {
    const SequenceParams* sp;
    int blocks_per_side[3];  // 8x8 blocks per macroblock side, per plane
};

Geometry geometry(const SequenceParams& sp) {
    Geometry g{&sp, {2, 2, 2}};
    for (int k = 1; k < 3; ++k) g.blocks_per_side[k] = 2 >> sp.shift(k);
    return g;
}

// What intra prediction of the 8x8 block at (bx, by) of plane `rec` predicts from: its decoded
// top row (when by > top, the slice's first row in this plane) and left column, each the DC value
// where it is missing, and the DC value (their rounded mean, else `neutral`).
struct IntraEdges {
    int t[8], l[8], dc;
};
IntraEdges intra_edges(const Image<int16_t>& rec, int bx, int by, int top, int neutral) {
    IntraEdges e;
    const bool has_top = by > top, has_left = bx > 0;
    int sum = 0;
    for (int i = 0; i < 8; ++i) {
        if (has_top) {
            e.t[i] = rec(bx + i, by - 1);
            sum += e.t[i];
        }
        if (has_left) {
            e.l[i] = rec(bx - 1, by + i);
            sum += e.l[i];
        }
    }
    const int count = 8 * (int(has_top) + int(has_left));
    e.dc = neutral;
    if (count) {
        const int v = sum + count / 2;  // rounded, floor division for negative chroma
        e.dc = v >= 0 ? v / count : -((-v + count - 1) / count);
    }
    for (int i = 0; i < 8; ++i) {
        if (!has_top) e.t[i] = e.dc;
        if (!has_left) e.l[i] = e.dc;
    }
    return e;
}

void intra_predict(const IntraEdges& e, int mode, Block& pred) {
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            int v = e.dc;
            if (mode == 1)
                v = e.t[x];
            else if (mode == 2)
                v = e.l[y];
            else if (mode == 3)
                v = (e.t[x] + e.l[y] + 1) >> 1;
            pred[y * 8 + x] = v;
        }
}

void intra_predict(const Image<int16_t>& rec, int bx, int by, int top, int mode, int neutral,
                   Block& pred) {
    intra_predict(intra_edges(rec, bx, by, top, neutral), mode, pred);
}

void load(const Image<int16_t>& p, int bx, int by, Block& b) {
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) b[y * 8 + x] = p(bx + x, by + y);
}

inline int position_class(int i) { return i == 0 ? 0 : i < 6 ? 1 : 2; }

// Levels of a block with at least one: the last's scan position (6 bits, a binary tree of
// models, high bit first), then from it down to 0 a significance flag (below the last), and for
// each level a greater-than-one flag, magnitude - 2 where greater, a bypass sign.
void code_levels(RangeEncoder& rc, Models& m, int type, const Block& levels) {
    int last = 0;
    for (int i = 63; i > 0; --i)
        if (levels[kZigzag[i]]) {
            last = i;
            break;
        }
    for (int bit = 5, node = 1; bit >= 0; --bit) {
        const int b = (last >> bit) & 1;
        rc.bit(m.last[type][node], b);
        node = 2 * node + b;
    }
    int ones = 0;
    bool any_greater = false;
    for (int i = last; i >= 0; --i) {
        const int32_t v = levels[kZigzag[i]];
        if (i < last)
            rc.bit(m.significant[type][significance_class(i)][levels[kZigzag[i + 1]] != 0], v != 0);
        if (!v) continue;
        const uint32_t a = uint32_t(std::abs(v));
        const int c = position_class(i);
        rc.bit(m.greater1[type][c][greater1_state(ones, any_greater)], a > 1);
        if (a > 1) encode_uint(rc, m.remaining[type][c], a - 2);
        ones += a == 1;
        any_greater = any_greater || a > 1;
        rc.bypass(v < 0);
    }
}

bool decode_levels(RangeDecoder& rc, Models& m, int type, Block& levels) {
    levels.fill(0);
    int last = 0;
    for (int bit = 5, node = 1; bit >= 0; --bit) {
        const int b = rc.bit(m.last[type][node]);
        last = (last << 1) | b;
        node = 2 * node + b;
    }
    int ones = 0;
    bool any_greater = false;
    for (int i = last; i >= 0; --i) {
        if (i < last &&
            !rc.bit(m.significant[type][significance_class(i)][levels[kZigzag[i + 1]] != 0]))
            continue;
        const int c = position_class(i);
        uint32_t a = 1;
        if (rc.bit(m.greater1[type][c][greater1_state(ones, any_greater)])) {
            uint32_t rest = 0;
            if (!decode_uint(rc, m.remaining[type][c], rest) || rest > uint32_t(kMaxLevel))
                return false;
            a = rest + 2;
        }
        ones += a == 1;
        any_greater = any_greater || a > 1;
        levels[kZigzag[i]] = rc.bypass() ? -int32_t(a) : int32_t(a);
    }
    return true;
}

void store(Image<int16_t>& p, int bx, int by, const Block& pred, const Block* residual, int lo,
           int hi) {
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            const int v = pred[y * 8 + x] + (residual ? (*residual)[y * 8 + x] : 0);
            p(bx + x, by + y) = int16_t(std::clamp(v, lo, hi));
        }
}

struct SliceJob {
    const Geometry* g;
    const Planes* source;     // encoder
    const Planes* predicted;  // null on key frames; else the output, predicted into
    Planes* out;
    const InterChoice* choices;  // encoder, inter frames: per macroblock, row-major
    int qp, skip_threshold;
    int mb_y0, mb_y1;
    std::vector<uint8_t>* coded;  // per plane, per 8x8 block
    const ModelCarry* carry;
    int slice;
    std::size_t blocks = 0, skipped = 0, intra = 0, macroblocks = 0;

    void mark(int k, int bx, int by, bool is_coded) const {
        coded[k][std::size_t(by / 8) * (out->p[k].width() / 8) + bx / 8] = is_coded;
    }
};

// An inter block holding only a few scattered +-1 levels costs more bits than the error it
// removes is worth: each level scores by the run of zeros before it (in scan order), and a block
// scoring under 4 is dropped (the decimation video encoders do; encoder-only).
bool worth_dropping(const Block& levels) {
    static constexpr int kRunScore[16] = {3, 2, 2, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    int score = 0, run = 0;
    for (int i = 0; i < 64; ++i) {
        const int32_t v = levels[kZigzag[i]];
        if (!v) {
            ++run;
            continue;
        }
        if (v > 1 || v < -1) return false;
        score += kRunScore[std::min(run, 15)];
        if (score >= 4) return false;
        run = 0;
    }
    return true;
}

// How much lower an intra macroblock's SAD must be than the reprojection's to be chosen: the
// bits intra costs beyond inter, weighted like a rate-distortion lambda for SAD (which doubles
// every 6 qp); 1024 at qp 40.
int intra_penalty(int qp) { return int(std::lround(1024.0 * std::exp2((qp - 40) / 6.0))); }

// The unnormalised Walsh-Hadamard transform of `count` values `step` apart, in place.
void hadamard8(int* v, int step) {
    for (int h = 1; h < 8; h *= 2)
        for (int i = 0; i < 8; i += 2 * h)
            for (int k = i; k < i + h; ++k) {
                const int x = v[k * step], y = v[(k + h) * step];
                v[k * step] = x + y, v[(k + h) * step] = x - y;
            }
}

// The 8x8 Hadamard transform of a row-major block, in place: rows, then columns.
void hadamard(int* d) {
    for (int l = 0; l < 8; ++l) hadamard8(d + l * 8, 1);
    for (int l = 0; l < 8; ++l) hadamard8(d + l, 8);
}

// Sum of absolute transformed differences (8x8 Hadamard): what a prediction's residual costs
// after the transform, closer than the SAD (encoder-only).
int satd(const Block& a, const Block& b) {
    int d[64];
    for (int i = 0; i < 64; ++i) d[i] = a[i] - b[i];
    hadamard(d);
    int s = 0;
    for (int i = 0; i < 64; ++i) s += std::abs(d[i]);
    return s / 8;
}

// satd(src, prediction) of each intra mode (encoder-only). The transform is linear, and the DC,
// vertical and horizontal predictions transform to one coefficient (64 dc), the first row
// (8 H t) and the first column (8 H l): one transform of the source gives those three exactly.
void intra_satds(const Block& src, const IntraEdges& e, int (&cost)[kModes]) {
    int hs[64];
    std::copy(src.begin(), src.end(), hs);
    hadamard(hs);
    int total = 0;
    for (int i = 0; i < 64; ++i) total += std::abs(hs[i]);
    int ht[8], hl[8];
    std::copy_n(e.t, 8, ht);
    std::copy_n(e.l, 8, hl);
    hadamard8(ht, 1);
    hadamard8(hl, 1);
    int row = total, column = total;
    for (int i = 0; i < 8; ++i) {
        row += std::abs(hs[i] - 8 * ht[i]) - std::abs(hs[i]);
        column += std::abs(hs[8 * i] - 8 * hl[i]) - std::abs(hs[8 * i]);
    }
    cost[0] = (total - std::abs(hs[0]) + std::abs(hs[0] - 64 * e.dc)) / 8;
    cost[1] = row / 8;
    cost[2] = column / 8;
    Block smooth;
    intra_predict(e, 3, smooth);
    cost[3] = satd(src, smooth);
}

// Sum of absolute differences of the block against a prediction.
int sad(const Block& a, const Block& b) {
    int s = 0;
    for (int i = 0; i < 64; ++i) s += std::abs(a[i] - b[i]);
    return s;
}

}  // namespace

void block_differences_row_reference(const BlockDifferencesRow& r, int b_begin, int b_end) {
    for (int b = b_begin; b < b_end; ++b) {
        int32_t sum = 0, largest = 0;
        for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x) {
                const std::ptrdiff_t at = std::ptrdiff_t(y) * r.stride + 8 * b + x;
                const int32_t d = std::abs(r.source[at] - r.prediction[at]);
                sum += d;
                largest = std::max(largest, d);
            }
        r.sum[b] = sum;
        r.largest[b] = largest;
    }
}

namespace {

// The decoded block: prediction plus the dequantised, inverse-transformed levels (none: the
// prediction alone, which counts as skipped for inter blocks).
void reconstruct(SliceJob& j, int k, int bx, int by, const Block& pred, const Block* levels,
                 bool intra, int32_t scale, int lo) {
    if (!levels) {
        store(j.out->p[k], bx, by, pred, nullptr, lo, 255);
        j.skipped += !intra;
        return;
    }
    Block coef, residual;
    dequantize(*levels, scale, coef);
    inverse_dct(coef, residual);
    store(j.out->p[k], bx, by, pred, &residual, lo, 255);
}

// Calls f(plane, x, y) for the 8x8 blocks of macroblock (mx, my) in coding order.
template <class F>
void for_each_block(const SliceJob& j, int mx, int my, const F& f) {
    for (int k = 0; k < 3; ++k) {
        const int n = j.g->blocks_per_side[k];
        for (int b = 0; b < n * n; ++b) f(k, mx * 8 * n + (b % n) * 8, my * 8 * n + (b / n) * 8);
    }
}

// Codes (Encode) or decodes one slice. Returns false on a corrupt slice (decoder only).
template <bool Encode, class Coder>
bool code_slice(SliceJob& j, Coder& rc) {
    const SequenceParams& sp = *j.g->sp;
    const int32_t scale = quant_scale(j.qp);
    Models m;
    j.carry->load(j.slice, m);
    const int cols = sp.mb_cols();
    std::vector<uint8_t> above_skip(cols, 0), above_intra(cols, 0);
    // Per 8x8 block of each plane: it has levels (the coded-block flag's context).
    std::vector<uint8_t> with_levels[3], modes[3];  // modes: intra mode + 1, 0 for inter blocks
    for (int k = 0; k < 3; ++k) {
        with_levels[k].assign(std::size_t(j.out->p[k].width() / 8) * (j.out->p[k].height() / 8), 0);
        modes[k].assign(with_levels[k].size(), 0);
    }
    for (int my = j.mb_y0; my < j.mb_y1; ++my) {
        int left_skip = 0, left_intra = 0;
        for (int mx = 0; mx < cols; ++mx) {
            ++j.macroblocks;
            const int ctx_skip = left_skip + (my > j.mb_y0 ? above_skip[mx] : 0);
            const int ctx_intra = left_intra + (my > j.mb_y0 ? above_intra[mx] : 0);
            bool skip = false, intra = j.predicted == nullptr;
            // Encoder: the inter decisions come from choose_inter; the levels are made here.
            Block src, pred, coef, levels, residual;
            Block inter_levels[12];  // encoder: an inter macroblock's blocks in coding order
            int inter_nonzero[12];
            if constexpr (Encode) {
                if (!intra) {
                    const InterChoice& choice = j.choices[std::size_t(my) * cols + mx];
                    skip = choice.skip;
                    intra = choice.intra;
                    // The inter blocks' levels, before the skip flag: a macroblock none of whose
                    // blocks keeps a level decodes to its prediction, so it is sent as skipped.
                    if (!skip && !intra) {
                        int b = 0;
                        bool any = false;
                        for_each_block(j, mx, my, [&](int k, int bx, int by) {
                            inter_nonzero[b] = 0;
                            if (!((choice.within | choice.quiet) >> b & 1)) {
                                load(j.source->p[k], bx, by, src);
                                load(j.predicted->p[k], bx, by, pred);
                                for (int i = 0; i < 64; ++i) residual[i] = src[i] - pred[i];
                                forward_dct(residual, coef);
                                inter_nonzero[b] =
                                    quantize(coef, scale, kInterRounding, inter_levels[b]);
                                if (inter_nonzero[b] && worth_dropping(inter_levels[b]))
                                    inter_nonzero[b] = 0;
                            }
                            any = any || inter_nonzero[b] > 0;
                            ++b;
                        });
                        skip = !any;
                    }
                }
                if (j.predicted) {
                    rc.bit(m.mb_skip[ctx_skip], skip);
                    if (!skip) rc.bit(m.mb_intra[ctx_intra], intra);
                }
            } else {
                if (j.predicted) {
                    skip = rc.bit(m.mb_skip[ctx_skip]);
                    if (!skip) intra = rc.bit(m.mb_intra[ctx_intra]);
                }
            }
            above_skip[mx] = left_skip = skip;
            above_intra[mx] = left_intra = intra;
            j.intra += intra;
            int block = -1;              // in the macroblock, in coding order
            bool levels_before = false;  // an earlier block of this macroblock has levels
            for (int k = 0; k < 3; ++k) {
                const int n = j.g->blocks_per_side[k];
                const int lo = k ? -255 : 0;
                const int top = j.mb_y0 * 8 * n;
                const int type = block_type(k, intra);
                for (int b = 0; b < n * n; ++b) {
                    const int bx = mx * 8 * n + (b % n) * 8, by = my * 8 * n + (b / n) * 8;
                    ++j.blocks;
                    ++block;
                    if (skip) {  // the output holds the prediction already
                        j.mark(k, bx, by, false);
                        ++j.skipped;
                        continue;
                    }
                    const int stride = j.out->p[k].width() / 8;
                    const std::size_t at = std::size_t(by / 8) * stride + bx / 8;
                    uint8_t& has_levels = with_levels[k][at];
                    const int ctx_mode = (bx > 0 ? modes[k][at - 1] : 0) +
                                         5 * (by > top ? modes[k][at - stride] : 0);
                    const int ctx_cbf = (bx > 0 ? (&has_levels)[-1] : 0) +
                                        (by > top ? (&has_levels)[-stride] : 0) +
                                        (k > 0 && levels_before ? 3 : 0);
                    int mode = 0;
                    if constexpr (Encode) {
                        load(j.source->p[k], bx, by, src);
                        if (intra) {
                            const IntraEdges edges =
                                intra_edges(j.out->p[k], bx, by, top, k ? 0 : 128);
                            int cost[kModes];
                            intra_satds(src, edges, cost);
                            for (int candidate = 1; candidate < kModes; ++candidate)
                                if (cost[candidate] < cost[mode]) mode = candidate;
                            intra_predict(edges, mode, pred);
                            rc.bit(m.mode[k > 0][ctx_mode][1], mode >> 1);
                            rc.bit(m.mode[k > 0][ctx_mode][2 + (mode >> 1)], mode & 1);
                            modes[k][at] = uint8_t(mode + 1);
                        } else {
                            load(j.predicted->p[k], bx, by, pred);
                        }
                        int nonzero = 0;
                        if (intra) {
                            for (int i = 0; i < 64; ++i) residual[i] = src[i] - pred[i];
                            forward_dct(residual, coef);
                            nonzero = quantize(coef, scale, kIntraRounding, levels);
                        } else {
                            nonzero = inter_nonzero[block];
                            if (nonzero) levels = inter_levels[block];
                        }
                        rc.bit(m.cbf[type][ctx_cbf], nonzero > 0);
                        has_levels = nonzero > 0;
                        levels_before = levels_before || nonzero > 0;
                        j.mark(k, bx, by, intra || nonzero);
                        if (nonzero) code_levels(rc, m, type, levels);
                        reconstruct(j, k, bx, by, pred, nonzero ? &levels : nullptr, intra, scale,
                                    lo);
                    } else {
                        if (intra) {
                            mode = rc.bit(m.mode[k > 0][ctx_mode][1]) << 1;
                            mode |= rc.bit(m.mode[k > 0][ctx_mode][2 + (mode >> 1)]);
                            modes[k][at] = uint8_t(mode + 1);
                            intra_predict(j.out->p[k], bx, by, top, mode, k ? 0 : 128, pred);
                        } else {
                            load(j.predicted->p[k], bx, by, pred);
                        }
                        const bool cbf = rc.bit(m.cbf[type][ctx_cbf]);
                        has_levels = cbf;
                        levels_before = levels_before || cbf;
                        j.mark(k, bx, by, intra || cbf);
                        if (cbf && !decode_levels(rc, m, type, levels)) return false;
                        reconstruct(j, k, bx, by, pred, cbf ? &levels : nullptr, intra, scale, lo);
                    }
                }
            }
        }
        if constexpr (!Encode) {
            if (rc.overrun() > 8) return false;
        }
    }
    j.carry->save(j.slice, m);
    return true;
}

// The inter decisions of every macroblock (in parallel over macroblock rows): skipped when every
// block stays within the skip threshold, intra when its best SAD (on source neighbours) clearly
// beats the reprojection's; intra is only tried where the reprojection is poor (more than 2
// levels off on average).
void choose_inter(const Geometry& g, const Planes& source, const Planes& predicted, int qp,
                  int skip_threshold, std::vector<InterChoice>& choices) {
    const SequenceParams& sp = *g.sp;
    const int cols = sp.mb_cols();
    choices.assign(std::size_t(cols) * sp.mb_rows(), {});
    const int32_t quiet_sad = quiet_below(quant_scale(qp), kInterRounding);
    parallel_for(
        0, sp.mb_rows(),
        [&](int row0, int row1) {
            // Per plane and 8-pixel strip of the macroblock row: each block's sum and largest.
            std::vector<int32_t> sums[3][2], largest[3][2];
            for (int k = 0; k < 3; ++k)
                for (int r = 0; r < g.blocks_per_side[k]; ++r) {
                    sums[k][r].resize(source.p[k].width() / 8);
                    largest[k][r].resize(source.p[k].width() / 8);
                }
            Block src, pred;
            for (int my = row0; my < row1; ++my) {
                int slice = 0;
                while (sp.slice_begin(slice + 1) <= my) ++slice;
                for (int k = 0; k < 3; ++k) {
                    const int n = g.blocks_per_side[k], stride = source.p[k].width();
                    for (int r = 0; r < n; ++r) {
                        const int y = (my * n + r) * 8;
                        block_differences_row({&source.p[k](0, y), &predicted.p[k](0, y), stride,
                                               stride / 8, sums[k][r].data(),
                                               largest[k][r].data()});
                    }
                }
                for (int mx = 0; mx < cols; ++mx) {
                    InterChoice& choice = choices[std::size_t(my) * cols + mx];
                    int inter_sad = 0, samples = 0, b = 0;
                    for (int k = 0; k < 3; ++k) {
                        const int n = g.blocks_per_side[k];
                        const int limit = k ? 2 * skip_threshold : skip_threshold;
                        for (int i = 0; i < n * n; ++i, ++b) {
                            const int at = mx * n + i % n;
                            const int32_t block_sad = sums[k][i / n][at];
                            inter_sad += block_sad;
                            samples += 64;
                            if (largest[k][i / n][at] <= limit) choice.within |= uint16_t(1 << b);
                            if (block_sad <= quiet_sad) choice.quiet |= uint16_t(1 << b);
                        }
                    }
                    choice.skip = choice.within == (1 << b) - 1;
                    if (choice.skip || inter_sad <= 2 * samples) continue;
                    int intra_sad = 0;
                    for (int k = 0; k < 3; ++k) {
                        const int n = g.blocks_per_side[k];
                        const int top = sp.slice_begin(slice) * 8 * n;
                        for (int i = 0; i < n * n; ++i) {
                            const int bx = mx * 8 * n + (i % n) * 8, by = my * 8 * n + (i / n) * 8;
                            load(source.p[k], bx, by, src);
                            const IntraEdges edges =
                                intra_edges(source.p[k], bx, by, top, k ? 0 : 128);
                            int best = 1 << 30;
                            for (int mode = 0; mode < kModes; ++mode) {
                                intra_predict(edges, mode, pred);
                                best = std::min(best, sad(src, pred));
                            }
                            intra_sad += best;
                        }
                    }
                    choice.intra = intra_sad + intra_penalty(qp) < inter_sad;
                }
            }
        },
        1);
}

std::vector<SliceJob> slice_jobs(const Geometry& g, const Planes* source, const Planes* predicted,
                                 Planes& out, int qp, int skip_threshold, Workspace& work,
                                 const ModelCarry& carry) {
    std::vector<SliceJob> jobs;
    for (int s = 0; s < g.sp->slices; ++s)
        jobs.push_back({&g, source, predicted, &out, work.inter_choices.data(), qp, skip_threshold,
                        g.sp->slice_begin(s), g.sp->slice_begin(s + 1), work.coded_blocks, &carry,
                        s});
    return jobs;
}

// Inter prediction, revealed pixels filled from the surface beside them.
void predict(const FrameContext& fc, ImageView<const float> depth,
             ImageView<const glm::vec2> motion, Planes& predicted, StreamStats& stats) {
    const StageTimer timer(stats.ms.predict);
    const SequenceParams& sp = *fc.sp;
    Reveal reveal{.depth = depth, .reference_depth = fc.reference->depth.view()};
    if (!depth.empty()) {
        ensure_size(fc.work->revealed, sp.width, sp.height);
        reveal.revealed = fc.work->revealed.view();
    }
    stats.revealed_pixels += predict_planes(fc.reference->planes, sp, motion, predicted, &reveal);
}

void prepare(const SequenceParams& sp, Planes& out, Workspace& work) {
    for (int k = 0; k < 3; ++k) {
        ensure_size(out.p[k], sp.plane_width(k), sp.plane_height(k));
        work.coded_blocks[k].resize(std::size_t(sp.plane_width(k) / 8) * (sp.plane_height(k) / 8));
    }
}

}  // namespace

ColorEncodeResult encode_color(const FrameContext& fc, const Planes& source,
                               ImageView<const float> depth, ImageView<const glm::vec2> motion,
                               int qp, int skip_threshold, Planes& out, std::vector<uint8_t>& bytes,
                               StreamStats& stats) {
    const SequenceParams& sp = *fc.sp;
    prepare(sp, out, *fc.work);
    // Predicted into the output, as the decoder does: a macroblock's decisions read its own
    // blocks' prediction before they are reconstructed, skipped blocks keep it.
    Planes& predicted = out;
    if (!fc.key) predict(fc, depth, motion, predicted, stats);
    const StageTimer timer(stats.ms.color);
    const std::size_t start = bytes.size();
    ByteWriter w(bytes);
    w.u8(uint8_t(qp));
    const Geometry g = geometry(sp);
    if (!fc.key) choose_inter(g, source, predicted, qp, skip_threshold, fc.work->inter_choices);
    const ModelCarry carry = fc.carry(&Picture::Models::colour);
    std::vector<SliceJob> jobs = slice_jobs(g, &source, fc.key ? nullptr : &predicted, out, qp,
                                            skip_threshold, *fc.work, carry);
    std::vector<uint8_t>& body = fc.work->section;
    body.clear();
    encode_slices(sp.slices, fc.work->slice_bytes, body, [&](int s, std::vector<uint8_t>& b) {
        RangeEncoder rc(b);
        code_slice<true>(jobs[s], rc);
        rc.finish();
    });
    ColorEncodeResult result;
    std::size_t blocks = 0, skipped = 0;
    for (const SliceJob& j : jobs) {
        blocks += j.blocks;
        skipped += j.skipped;
        result.intra_macroblocks += j.intra;
        result.macroblocks += j.macroblocks;
    }
    const bool all_skipped = !fc.key && skipped == blocks;
    w.u8(all_skipped ? kAllSkipped : 0);
    if (all_skipped) carry.pass_on(sp.slices);  // no slice is coded
    if (!all_skipped) {
        w.bytes(body);
        deblock(out, fc.work->coded_blocks, qp);
    }
    stats.blocks += blocks;
    stats.blocks_skipped += skipped;
    stats.intra_blocks += result.intra_macroblocks;
    stats.color_bits += 8 * (bytes.size() - start);
    return result;
}

Status decode_color(const FrameContext& fc, ImageView<const float> depth,
                    ImageView<const glm::vec2> motion, std::span<const uint8_t> in, Planes& out,
                    StreamStats& stats) {
    const SequenceParams& sp = *fc.sp;
    prepare(sp, out, *fc.work);
    ByteReader r(in, "colour section");
    const int qp = r.u8();
    const uint8_t flags = r.u8();
    if (!r.ok()) return Status::error(r.error());
    if (qp > 51) return Status::error("colour section: qp " + std::to_string(qp) + " is above 51");
    if (flags & ~kAllSkipped)
        return Status::error("colour section: unknown flags " + std::to_string(flags));
    if ((flags & kAllSkipped) && fc.key)
        return Status::error("colour section: a key frame cannot skip its blocks");
    // The prediction goes to the output, where skipped blocks keep it (a block reads only its
    // own prediction; intra blocks read the decoded blocks beside them).
    Planes& predicted = out;
    if (!fc.key) predict(fc, depth, motion, predicted, stats);
    const StageTimer timer(stats.ms.color);
    const ModelCarry carry = fc.carry(&Picture::Models::colour);
    const std::size_t blocks =
        std::size_t(sp.mb_cols()) * sp.mb_rows() * (4 + 2 * (sp.chroma == Chroma::C420 ? 1 : 4));
    if (flags & kAllSkipped) {
        if (r.remaining()) return Status::error("colour section: bytes after an all-skipped flag");
        stats.blocks += blocks;
        stats.blocks_skipped += blocks;
    } else {
        std::vector<std::span<const uint8_t>> slices;
        if (!read_slices(r, sp.slices, slices)) return Status::error(r.error());
        const Geometry g = geometry(sp);
        std::vector<SliceJob> jobs =
            slice_jobs(g, nullptr, fc.key ? nullptr : &predicted, out, qp, 0, *fc.work, carry);
        REPRISE_TRY(
            decode_slices(slices, "colour section", [&](int s, std::span<const uint8_t> bytes) {
                RangeDecoder rc(bytes);
                return code_slice<false>(jobs[s], rc);
            }));
        for (const SliceJob& j : jobs) {
            stats.blocks += j.blocks;
            stats.blocks_skipped += j.skipped;
            stats.intra_blocks += j.intra;
        }
        deblock(out, fc.work->coded_blocks, qp);
    }
    stats.color_bits += 8 * in.size();
    return {};
}

}  // namespace reprise::codec
