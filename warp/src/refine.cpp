// Motion refinement of interpolation (RefineOptions): optical flow where the warped sides
// disagree, used per pixel where its two sides agree better than the rendered motion's.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/video/tracking.hpp>
#include <utility>

#include "reprise/core/parallel.hpp"
#include "reprise/warp/refine.hpp"
#include "reprise/warp/sample.hpp"

namespace reprise::warp {

namespace {

constexpr int kSurveyStep = 2;      // the survey looks at every 2nd pixel of every 2nd row
constexpr int kMinDisagreeing = 4;  // surveyed pixels a tile needs besides its share
constexpr float kInf = std::numeric_limits<float>::infinity();

glm::vec3 display(glm::vec4 c, bool perceptual) {
    return {MotionRefiner::display(c.r, perceptual), MotionRefiner::display(c.g, perceptual),
            MotionRefiner::display(c.b, perceptual)};
}

float largest_difference(glm::vec4 a, glm::vec4 b, bool perceptual) {
    const glm::vec3 d = glm::abs(display(a, perceptual) - display(b, perceptual));
    return std::max({d.r, d.g, d.b});
}

float mean_difference(glm::vec4 a, glm::vec4 b, bool perceptual) {
    const glm::vec3 d = glm::abs(display(a, perceptual) - display(b, perceptual));
    return (d.r + d.g + d.b) * (1.0f / 3.0f);
}

// One surface (tighter than the blend's kSameSurface: surfaces whose depth changed between the
// frames are not surveyed), or background on both sides.
bool same_surface(float za, float zb) {
    if (std::isinf(za) && std::isinf(zb)) return true;
    return std::abs(za - zb) <= 0.02f * std::min(za, zb);
}

using Box = RefineBox;

// Both candidates' colour and error at one output pixel, or +inf error where a side falls
// outside its frame.
struct Candidate {
    glm::vec4 color;
    float error;
};

Candidate along(const GBufferView& a, const GBufferView& b, glm::vec2 q, glm::vec2 a_to_b, float s,
                bool perceptual) {
    const glm::vec2 pa = q - s * a_to_b, pb = q + (1.0f - s) * a_to_b;
    const Bilinear ta = bilinear_taps(pa.x, pa.y, a.width(), a.height());
    const Bilinear tb = bilinear_taps(pb.x, pb.y, b.width(), b.height());
    if (!ta.inside || !tb.inside) return {glm::vec4(0.0f), kInf};
    const glm::vec4 ca = bilinear_fetch(a.color, ta), cb = bilinear_fetch(b.color, tb);
    const float e = mean_difference(ca, cb, perceptual);
    if (!std::isfinite(e)) return {glm::vec4(0.0f), kInf};
    return {(1.0f - s) * ca + s * cb, e};
}

}  // namespace

struct MotionRefiner::State {
    int tile = 16, tiles_x = 0, tiles_y = 0;
    bool perceptual = false;                 // colours on FrucOptions::perceptual's scale
    std::vector<uint8_t> flagged;            // tiles whose sides disagree
    std::vector<int> surveyed, disagreeing;  // per tile: pixels surveyed, those that disagree
    std::vector<uint8_t> wanted;             // flagged tiles and their neighbours
    std::vector<int> label;  // tiles to decide (flagged and their neighbours): box, else -1
    std::vector<int> stack;
    std::vector<Box> boxes;
    std::vector<int> decided;  // tiles whose pixels were decided (apply() visits these)
    // Per pixel of the decided tiles (tile * tile each, in decided's order): the flow's colour,
    // and whether it was chosen.
    std::vector<glm::vec4> chosen_color;
    std::vector<uint8_t> chosen;
    std::vector<float> box_disagreeing;        // per box: disagreeing pixels surveyed
    std::vector<std::pair<float, int>> order;  // boxes by disagreement per flow pixel
    cv::Mat grey_a, grey_b, flow_field;
    // Per pixel of the box being decided (its own size): the rendered motion's error (-1: not
    // one surface on both sides), the flow's error and colour.
    std::vector<float> error_rendered, error_flow;
    std::vector<glm::vec4> color_flow;

    void size_tiles(int w, int h, const RefineOptions& options) {
        const RefineTiles t = RefineTiles::of(w, h, options);
        tile = t.size, tiles_x = t.x, tiles_y = t.y;
        flagged.assign(t.count(), 0);
    }

    // Flags the tiles whose counts say the sides show one surface in different colours; returns
    // how many.
    std::size_t flag(const RefineOptions& options) {
        std::size_t total = 0;
        for (std::size_t t = 0; t < flagged.size(); ++t) {
            flagged[t] = disagreeing[t] >= kMinDisagreeing &&
                         float(disagreeing[t]) >= options.tile_share * float(surveyed[t]);
            total += flagged[t];
        }
        return total;
    }

    // Counts each tile's surveyed and disagreeing pixels (MotionRefiner::plan), then flags.
    std::size_t survey(ImageView<const glm::vec4> ca, ImageView<const float> za,
                       ImageView<const uint8_t> covered_a, ImageView<const glm::vec4> cb,
                       ImageView<const float> zb, ImageView<const uint8_t> covered_b,
                       const RefineOptions& options) {
        const int w = ca.width, h = ca.height;
        size_tiles(w, h, options);
        surveyed.assign(flagged.size(), 0);
        disagreeing.assign(flagged.size(), 0);
        parallel_for(
            0, tiles_y,
            [&](int t0, int t1) {
                for (int ty = t0; ty < t1; ++ty) {
                    int* surveyed_row = surveyed.data() + std::size_t(ty) * tiles_x;
                    int* disagreeing_row = disagreeing.data() + std::size_t(ty) * tiles_x;
                    const int y_end = std::min(h, (ty + 1) * tile);
                    for (int y = ty * tile + kSurveyStep / 2; y < y_end; y += kSurveyStep)
                        for (int x = kSurveyStep / 2; x < w; x += kSurveyStep) {
                            if (!covered_a.empty() && !(covered_a(x, y) && covered_b(x, y)))
                                continue;
                            if (!same_surface(za(x, y), zb(x, y))) continue;
                            const int tx = x / tile;
                            ++surveyed_row[tx];
                            disagreeing_row[tx] +=
                                largest_difference(ca(x, y), cb(x, y), perceptual) >
                                options.threshold;
                        }
                }
            },
            1);
        return flag(options);
    }

    // Flagged tiles (and their neighbours), in boxes (connected groups, with margin, merged
    // where they overlap); label[] says which box decides each tile.
    void make_boxes(int w, int h, int margin, bool neighbours) {
        const int n = tiles_x * tiles_y;
        label.assign(n, -1);
        wanted.assign(n, 0);
        for (int ty = 0; ty < tiles_y; ++ty)
            for (int tx = 0; tx < tiles_x; ++tx) {
                if (!flagged[std::size_t(ty) * tiles_x + tx]) continue;
                const int ring = neighbours ? 1 : 0;
                for (int dy = -ring; dy <= ring; ++dy)
                    for (int dx = -ring; dx <= ring; ++dx) {
                        const int x = tx + dx, y = ty + dy;
                        if (x >= 0 && y >= 0 && x < tiles_x && y < tiles_y)
                            wanted[std::size_t(y) * tiles_x + x] = 1;
                    }
            }
        boxes.clear();
        for (int start = 0; start < n; ++start) {
            if (!wanted[start] || label[start] >= 0) continue;
            const int id = int(boxes.size());
            Box tiles{start % tiles_x, start / tiles_x, start % tiles_x + 1, start / tiles_x + 1};
            stack.assign(1, start);
            label[start] = id;
            while (!stack.empty()) {
                const int t = stack.back();
                stack.pop_back();
                const int tx = t % tiles_x, ty = t / tiles_x;
                tiles = {std::min(tiles.x0, tx), std::min(tiles.y0, ty), std::max(tiles.x1, tx + 1),
                         std::max(tiles.y1, ty + 1)};
                const int next[4][2] = {{tx - 1, ty}, {tx + 1, ty}, {tx, ty - 1}, {tx, ty + 1}};
                for (const auto& p : next) {
                    if (p[0] < 0 || p[1] < 0 || p[0] >= tiles_x || p[1] >= tiles_y) continue;
                    const int u = p[1] * tiles_x + p[0];
                    if (wanted[u] && label[u] < 0) label[u] = id, stack.push_back(u);
                }
            }
            boxes.push_back(
                {std::max(0, tiles.x0 * tile - margin), std::max(0, tiles.y0 * tile - margin),
                 std::min(w, tiles.x1 * tile + margin), std::min(h, tiles.y1 * tile + margin)});
        }
        // Overlapping boxes become one (their tiles follow) where that costs no more pixels
        // than the two apart.
        for (bool merged = true; merged;) {
            merged = false;
            for (std::size_t i = 0; i < boxes.size() && !merged; ++i)
                for (std::size_t j = i + 1; j < boxes.size() && !merged; ++j) {
                    if (!boxes[i].overlaps(boxes[j])) continue;
                    Box& b = boxes[i];
                    const Box& o = boxes[j];
                    const Box both{std::min(b.x0, o.x0), std::min(b.y0, o.y0), std::max(b.x1, o.x1),
                                   std::max(b.y1, o.y1)};
                    if (both.area() > b.area() + o.area()) continue;
                    b = both;
                    for (int& l : label) {
                        if (l == int(j))
                            l = int(i);
                        else if (l > int(j))
                            --l;
                    }
                    boxes.erase(boxes.begin() + std::ptrdiff_t(j));
                    merged = true;
                }
        }
    }

    // Keeps the boxes that disagree most per pixel of flow within `budget` pixels; the tiles of
    // the others are not decided. Returns the flagged tiles left out.
    std::size_t keep_within(std::size_t budget) {
        std::size_t total = 0;
        for (const Box& box : boxes) total += std::size_t(box.area());
        if (total <= budget) return 0;
        box_disagreeing.assign(boxes.size(), 0.0f);
        for (std::size_t t = 0; t < label.size(); ++t)
            if (label[t] >= 0 && flagged[t])
                box_disagreeing[std::size_t(label[t])] += float(disagreeing[t]);
        order.clear();
        for (std::size_t i = 0; i < boxes.size(); ++i)
            order.emplace_back(-box_disagreeing[i] / float(boxes[i].area()), int(i));
        std::sort(order.begin(), order.end());
        std::size_t used = 0, left_out = 0;
        for (const auto& [score, i] : order) {
            const std::size_t area = std::size_t(boxes[std::size_t(i)].area());
            if (used + area <= budget) {
                used += area;
                continue;
            }
            boxes[std::size_t(i)] = {0, 0, 0, 0};
            for (std::size_t t = 0; t < label.size(); ++t)
                if (label[t] == i) left_out += flagged[t], label[t] = -1;
        }
        return left_out;
    }

    // From the flagged tiles: the boxes and the tiles they decide; false where none is flagged.
    bool plan(int w, int h, std::size_t flagged_tiles, const RefineOptions& options,
              FrucCounters& counters) {
        decided.clear();
        if (flagged_tiles == 0) {
            boxes.clear();
            label.assign(flagged.size(), -1);
            ++counters.refine_skipped;
            return false;
        }
        ++counters.refined_frames;
        counters.refine_tiles += flagged_tiles;
        make_boxes(w, h, std::max(options.margin, 0), options.neighbours);
        const double share = std::clamp(double(options.max_flow_share), 0.0, 1.0);
        counters.refine_tiles_left_out += keep_within(std::size_t(share * double(w) * h));
        for (int t = 0; t < tiles_x * tiles_y; ++t)
            if (label[t] >= 0) decided.push_back(t);
        for (const Box& box : boxes) counters.flow_pixels += std::size_t(box.area());
        return true;
    }

    void grey_crop(const GBufferView& f, const Box& box, cv::Mat& out) {
        out.create(box.y1 - box.y0, box.x1 - box.x0, CV_8U);
        for (int y = box.y0; y < box.y1; ++y) {
            uint8_t* row = out.ptr<uint8_t>(y - box.y0);
            const glm::vec4* c = f.color.row(y);
            for (int x = box.x0; x < box.x1; ++x)
                row[x - box.x0] = MotionRefiner::grey(c[x], perceptual);
        }
    }

    // DIS flow from `from` to `to` on the crops, seeded with `seed` (motion from->to, may be
    // empty; non-finite values seed 0).
    void estimate(const cv::Mat& from, const cv::Mat& to, ImageView<const glm::vec2> seed,
                  float seed_sign, const Box& box, cv::Mat& flow_out) {
        flow_out.create(from.rows, from.cols, CV_32FC2);
        for (int y = box.y0; y < box.y1; ++y) {
            cv::Vec2f* row = flow_out.ptr<cv::Vec2f>(y - box.y0);
            for (int x = box.x0; x < box.x1; ++x) {
                glm::vec2 m = seed.empty() ? glm::vec2(0.0f) : seed(x, y) * seed_sign;
                if (!std::isfinite(m.x) || !std::isfinite(m.y)) m = glm::vec2(0.0f);
                row[x - box.x0] = cv::Vec2f(m.x, m.y);
            }
        }
        // A new DIS each time: one kept across calls gave flows that depend on the calls before
        // (OpenCV 4.6: a 96x64 box after an 80x56 one), so a frame's refinement depended on the
        // frames refined before it.
        cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_FAST)->calc(from, to, flow_out);
    }

    // Errors of the rendered motion and the flow, and the flow's colour, over a box.
    void evaluate(const GBufferView& a, const GBufferView& b, float s, const WarpedSide& side_a,
                  const WarpedSide& side_b, const Box& box) {
        const int bw = box.x1 - box.x0;
        const std::size_t n = std::size_t(box.area());
        error_rendered.resize(n), error_flow.resize(n), color_flow.resize(n);
        parallel_for(box.y0, box.y1, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                const cv::Vec2f* f = flow_field.ptr<cv::Vec2f>(y - box.y0);
                const std::size_t row = std::size_t(y - box.y0) * bw;
                for (int x = box.x0; x < box.x1; ++x) {
                    const std::size_t i = row + std::size_t(x - box.x0);
                    const bool one_surface = side_a.covered(x, y) && side_b.covered(x, y) &&
                                             same_surface(side_a.depth(x, y), side_b.depth(x, y));
                    const float e = one_surface ? mean_difference(side_a.color(x, y),
                                                                  side_b.color(x, y), perceptual)
                                                : -1.0f;
                    error_rendered[i] = std::isfinite(e) ? e : -1.0f;
                    const cv::Vec2f m = f[x - box.x0];
                    const Candidate c = along(a, b, glm::vec2(float(x) + 0.5f, float(y) + 0.5f),
                                              -glm::vec2(m[0], m[1]), s, perceptual);
                    error_flow[i] = c.error, color_flow[i] = c.color;
                }
            }
        });
    }

    // Per pixel of the box's tiles, errors averaged over 3x3 (within the box): the flow wins
    // where it beats the rendered motion by the margin. Writes the chosen pixels of the box's
    // tiles (their slots of chosen, in decided's order); returns the winners.
    std::size_t decide(const Box& box, int id) {
        const int bw = box.x1 - box.x0;
        const std::size_t area = std::size_t(tile) * tile;
        std::size_t won = 0;
        for (std::size_t slot = 0; slot < decided.size(); ++slot) {
            const int t = decided[slot];
            if (label[t] != id) continue;
            uint8_t* pick = chosen.data() + slot * area;
            glm::vec4* flow_color = chosen_color.data() + slot * area;
            std::fill(pick, pick + area, uint8_t(0));
            const int tx0 = (t % tiles_x) * tile, ty0 = (t / tiles_x) * tile;
            const int tx1 = std::min(box.x1, tx0 + tile), ty1 = std::min(box.y1, ty0 + tile);
            for (int y = ty0; y < ty1; ++y)
                for (int x = tx0; x < tx1; ++x) {
                    const std::size_t i = std::size_t(y - box.y0) * bw + std::size_t(x - box.x0);
                    if (error_rendered[i] < 0.0f) continue;
                    float rendered = 0.0f, flowed = 0.0f;
                    int count = 0;
                    for (int v = std::max(box.y0, y - 1); v <= std::min(box.y1 - 1, y + 1); ++v)
                        for (int u = std::max(box.x0, x - 1); u <= std::min(box.x1 - 1, x + 1);
                             ++u) {
                            const std::size_t j =
                                std::size_t(v - box.y0) * bw + std::size_t(u - box.x0);
                            if (error_rendered[j] < 0.0f) continue;
                            rendered += error_rendered[j];
                            flowed += error_flow[j];
                            ++count;
                        }
                    if (!(flowed / float(count) + kRefineWinMargin < rendered / float(count)))
                        continue;
                    const std::size_t k = std::size_t(y - ty0) * tile + std::size_t(x - tx0);
                    pick[k] = 1;
                    flow_color[k] = color_flow[i];
                    ++won;
                }
        }
        return won;
    }
};

MotionRefiner::MotionRefiner() : state_(std::make_unique<State>()) {}
MotionRefiner::~MotionRefiner() = default;

bool MotionRefiner::prepare(const GBufferView& a, const GBufferView& b, float s,
                            const WarpedSide& side_a, const WarpedSide& side_b,
                            const RefineOptions& options, bool perceptual, FrucCounters& counters) {
    State& st = *state_;
    st.perceptual = perceptual;
    const auto start = std::chrono::steady_clock::now();
    auto finish = [&](bool apply) {
        counters.refine_ms +=
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        if (!apply) st.decided.clear();
        return apply;
    };
    const std::size_t flagged = st.survey(side_a.color, side_a.depth, side_a.covered, side_b.color,
                                          side_b.depth, side_b.covered, options);
    if (!st.plan(b.width(), b.height(), flagged, options, counters)) return finish(false);
    const std::size_t tile_area = std::size_t(st.tile) * st.tile;
    st.chosen.resize(st.decided.size() * tile_area);
    st.chosen_color.resize(st.decided.size() * tile_area);
    std::size_t won = 0;
    for (std::size_t i = 0; i < st.boxes.size(); ++i) {
        const Box& box = st.boxes[i];
        if (box.area() == 0) continue;
        st.grey_crop(a, box, st.grey_a);
        st.grey_crop(b, box, st.grey_b);
        // b(p) ~ a(p + flow): b's backward motion, followed from the in-between instant.
        st.estimate(st.grey_b, st.grey_a, b.motion, 1.0f, box, st.flow_field);
        st.evaluate(a, b, s, side_a, side_b, box);
        won += st.decide(box, int(i));
    }
    counters.refined_pixels += won;
    return finish(won > 0);
}

void MotionRefiner::apply(ImageView<glm::vec4> color) const {
    const State& st = *state_;
    const std::size_t area = std::size_t(st.tile) * st.tile;
    for (std::size_t slot = 0; slot < st.decided.size(); ++slot) {
        const int t = st.decided[slot];
        const int x0 = (t % st.tiles_x) * st.tile, y0 = (t / st.tiles_x) * st.tile;
        const int x1 = std::min(color.width, x0 + st.tile),
                  y1 = std::min(color.height, y0 + st.tile);
        const uint8_t* pick = st.chosen.data() + slot * area;
        const glm::vec4* flow_color = st.chosen_color.data() + slot * area;
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                const std::size_t k = std::size_t(y - y0) * st.tile + std::size_t(x - x0);
                if (pick[k]) color(x, y) = flow_color[k];
            }
    }
}

bool MotionRefiner::pictures_differ(const GBufferView& a, const GBufferView& b,
                                    const RefineOptions& options) {
    state_->perceptual = false;
    return state_->survey(a.color, a.depth, {}, b.color, b.depth, {}, options) > 0;
}

void MotionRefiner::region(Image<uint8_t>& mask, int width, int height) const {
    const State& st = *state_;
    mask.assign(width, height, 0);
    if (st.flagged.size() != std::size_t(st.tiles_x) * st.tiles_y) return;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const int tx = x / st.tile, ty = y / st.tile;
            if (tx < st.tiles_x && ty < st.tiles_y)
                mask(x, y) = st.flagged[std::size_t(ty) * st.tiles_x + tx];
        }
}

RefineTiles RefineTiles::of(int width, int height, const RefineOptions& options) {
    const int size = std::max(options.tile, 4);
    return {size, (std::max(width, 0) + size - 1) / size, (std::max(height, 0) + size - 1) / size};
}

float MotionRefiner::display(float value, bool perceptual) {
    // On the perceptual scale the value is the square root of the linear light already.
    const float c = value > 0.0f ? std::min(value, 1.0f) : 0.0f;
    return perceptual ? 1.138f * c - 0.138f * (c * c) : 1.138f * std::sqrt(c) - 0.138f * c;
}

uint8_t MotionRefiner::grey(glm::vec4 c, bool perceptual) {
    if (perceptual) c = glm::vec4(glm::vec3(c) * glm::abs(glm::vec3(c)), c.a);
    const float luma = display(0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b, false);
    return uint8_t(luma * 255.0f + 0.5f);
}

const std::vector<RefineBox>& MotionRefiner::plan(int width, int height,
                                                  std::span<const int> surveyed,
                                                  std::span<const int> disagreeing,
                                                  const RefineOptions& options,
                                                  FrucCounters& counters) {
    State& st = *state_;
    st.size_tiles(width, height, options);
    REPRISE_ASSERT(surveyed.size() == st.flagged.size() && disagreeing.size() == st.flagged.size());
    st.surveyed.assign(surveyed.begin(), surveyed.end());
    st.disagreeing.assign(disagreeing.begin(), disagreeing.end());
    st.plan(width, height, st.flag(options), options, counters);
    st.decided.clear();  // apply() follows prepare() alone: the caller decides these boxes
    return st.boxes;
}

std::span<const int> MotionRefiner::tile_boxes() const { return state_->label; }

void MotionRefiner::flow(ImageView<const uint8_t> grey_b, ImageView<const uint8_t> grey_a,
                         ImageView<const glm::vec2> seed, Image<glm::vec2>& flow) {
    State& st = *state_;
    const int w = grey_b.width, h = grey_b.height;
    REPRISE_ASSERT(grey_a.width == w && grey_a.height == h && seed.width == w && seed.height == h);
    const auto wrap = [](ImageView<const uint8_t> v) {
        return cv::Mat(v.height, v.width, CV_8U, const_cast<uint8_t*>(v.data),
                       std::size_t(v.stride));
    };
    st.estimate(wrap(grey_b), wrap(grey_a), seed, 1.0f, Box{0, 0, w, h}, st.flow_field);
    flow.resize(w, h);
    for (int y = 0; y < h; ++y) {
        const cv::Vec2f* row = st.flow_field.ptr<cv::Vec2f>(y);
        for (int x = 0; x < w; ++x) flow(x, y) = glm::vec2(row[x][0], row[x][1]);
    }
}

void MotionRefiner::forget_region() {
    std::fill(state_->flagged.begin(), state_->flagged.end(), 0);
}

}  // namespace reprise::warp
