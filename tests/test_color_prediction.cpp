// The codec's colour prediction where the reference did not see a pixel (codec/src/predict.cpp,
// fill_revealed): a revealed strip takes the surface beside it, mirrored about the strip's edge.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../codec/src/internal.hpp"

namespace reprise::codec {
namespace {

constexpr int kW = 64, kH = 16;

// A square at depth 1 over a background at depth 10, its left edge at `left` (10 pixels wide).
Image<float> square_depth(int left) {
    Image<float> depth(kW, kH);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) depth(x, y) = x >= left && x < left + 10 ? 1.0f : 10.0f;
    return depth;
}

// Every plane's prediction is its column index.
Planes column_planes(const SequenceParams& sp) {
    Planes planes;
    for (int k = 0; k < 3; ++k) {
        planes.p[k].resize(sp.plane_width(k), sp.plane_height(k));
        for (int y = 0; y < planes.p[k].height(); ++y)
            for (int x = 0; x < planes.p[k].width(); ++x) planes.p[k](x, y) = int16_t(x);
    }
    return planes;
}

SequenceParams sequence() {
    SequenceParams sp;
    sp.width = kW;
    sp.height = kH;
    return sp;
}

// The square moved from x = 20 to x = 30: the background at 20..29 was behind it. Each of those
// pixels takes the column mirrored about x = 19.5 (the nearest background the reference saw);
// chroma (4:2:0) the same on its half-width grid (about 9.5).
TEST(ColorPrediction, ARevealedStripMirrorsTheSurfaceBesideIt) {
    const SequenceParams sp = sequence();
    const Image<float> reference = square_depth(20), depth = square_depth(30);
    Image<glm::vec2> motion(kW, kH);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x)
            motion(x, y) = depth(x, y) < 5.0f ? glm::vec2(-10.0f, 0.0f) : glm::vec2(0.0f);
    Planes planes = column_planes(sp);
    Image<uint8_t> revealed(kW, kH);
    EXPECT_EQ(
        fill_revealed(sp, motion.view(), {depth.view(), reference.view(), revealed.view()}, planes),
        std::size_t(10 * kH));
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const bool strip = x >= 20 && x < 30;
            EXPECT_EQ(revealed(x, y), strip) << x << "," << y;
            EXPECT_EQ(planes.p[0](x, y), strip ? 39 - x : x) << x << "," << y;
        }
    for (int k = 1; k < 3; ++k)
        for (int y = 0; y < kH / 2; ++y)
            for (int x = 0; x < kW / 2; ++x)
                EXPECT_EQ(planes.p[k](x, y), x >= 10 && x < 15 ? 19 - x : x) << k << ":" << x;
}

// A static frame reveals nothing and changes nothing; NaN depth or motion reveals nothing either;
// a landing off the reference's edge counts as seen (the prediction clamps there).
TEST(ColorPrediction, NothingIsRevealedWhereTheReferenceSawEverything) {
    const SequenceParams sp = sequence();
    Image<float> depth = square_depth(20);
    Image<glm::vec2> motion(kW, kH);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) motion(x, y) = {0.0f, 0.0f};
    const Planes before = column_planes(sp);
    Planes planes = before;
    Image<uint8_t> revealed(kW, kH);
    const Reveal reveal{depth.view(), depth.view(), revealed.view()};
    EXPECT_EQ(fill_revealed(sp, motion.view(), reveal, planes), 0u);
    for (int y = 0; y < kH; ++y) {
        depth(25, y) = NAN;
        motion(5, y) = {NAN, 0.0f};
        motion(40, y) = {-100.0f, 0.0f};  // off the left edge
        motion(45, y) = {-22.0f, 0.0f};   // lands on the square: revealed, takes the background
                                          // beside it
    }
    EXPECT_EQ(fill_revealed(sp, motion.view(), reveal, planes), std::size_t(kH));
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            EXPECT_EQ(revealed(x, y), x == 45) << x << "," << y;
            EXPECT_EQ(planes.p[0](x, y), x == 45 ? 44 : before.p[0](x, y)) << x << "," << y;
        }
}

// The codec fills while it predicts, row by row on the pool's threads; the same fill over the whole
// prediction afterwards is its reference. Odd sizes, 4:2:0 and 4:4:4, random reference and motion.
TEST(ColorPrediction, TheFusedFillEqualsTheFillAfterThePrediction) {
    std::mt19937 rng(7);
    for (Chroma chroma : {Chroma::C420, Chroma::C444})
        for (auto [w, h] : {std::pair{61, 37}, std::pair{160, 96}}) {
            SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
            SequenceParams sp;
            sp.width = w;
            sp.height = h;
            sp.chroma = chroma;
            Planes reference;
            for (int k = 0; k < 3; ++k) {
                reference.p[k].resize(sp.plane_width(k), sp.plane_height(k));
                for (std::size_t i = 0; i < reference.p[k].pixel_count(); ++i)
                    reference.p[k].data()[i] = int16_t(rng() % 256) - (k ? 128 : 0);
            }
            Image<float> depth(w, h), reference_depth(w, h);
            Image<glm::vec2> motion(w, h);
            std::uniform_real_distribution<float> shift(-6.0f, 6.0f);
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    const bool near = (x / 12 + y / 9) % 3 == 0, was_near = (x / 12) % 2 == 0;
                    depth(x, y) = near ? 1.0f + 0.001f * float(x) : 10.0f;
                    reference_depth(x, y) = was_near ? 1.0f : (y % 11 == 0 ? INFINITY : 10.0f);
                    motion(x, y) = {shift(rng), shift(rng) * 0.5f};
                }
            Image<uint8_t> fused_mask(w, h), mask(w, h);
            Planes fused, after;
            const Reveal reveal{depth.view(), reference_depth.view(), fused_mask.view()};
            const std::size_t n = predict_planes(reference, sp, motion.view(), fused, &reveal);
            predict_planes(reference, sp, motion.view(), after);
            EXPECT_EQ(fill_revealed(sp, motion.view(),
                                    {depth.view(), reference_depth.view(), mask.view()}, after),
                      n);
            EXPECT_GT(n, std::size_t(w * h / 10));
            for (int k = 0; k < 3; ++k)
                EXPECT_TRUE(std::equal(fused.p[k].data(),
                                       fused.p[k].data() + fused.p[k].pixel_count(),
                                       after.p[k].data()))
                    << "plane " << k;
        }
}

}  // namespace
}  // namespace reprise::codec
