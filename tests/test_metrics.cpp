#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "reprise/core/frame.hpp"
#include "reprise/core/metrics.hpp"

using namespace reprise;

namespace {

Image<glm::vec3> flat(int w, int h, float v) { return Image<glm::vec3>(w, h, glm::vec3(v)); }

// A smooth, textured display image in [0.2, 0.8].
Image<glm::vec3> pattern(int w, int h) {
    Image<glm::vec3> img(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            img(x, y) = glm::vec3(0.5f + 0.3f * std::sin(x * 0.11f) * std::cos(y * 0.07f),
                                  0.5f + 0.3f * std::sin(0.05f * (x + y)), 0.2f + 0.6f * x / w);
    return img;
}

// `base` plus the same zero-mean noise pattern scaled by `amplitude`.
Image<glm::vec3> noisy(const Image<glm::vec3>& base, float amplitude, unsigned seed = 7) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    Image<glm::vec3> img = base;
    for (int y = 0; y < img.height(); ++y)
        for (int x = 0; x < img.width(); ++x)
            img(x, y) =
                glm::clamp(img(x, y) + amplitude * glm::vec3(u(rng), u(rng), u(rng)), 0.0f, 1.0f);
    return img;
}

double map_max(const Image<float>& map) {
    double m = 0;
    for (int y = 0; y < map.height(); ++y)
        for (int x = 0; x < map.width(); ++x) m = std::max(m, double(map(x, y)));
    return m;
}

}  // namespace

TEST(Metrics, ToDisplayEncodesClampedLinearAndZeroesNaN) {
    Image<glm::vec4> linear(4, 1);
    linear(0, 0) = {0.0f, 1.0f, 0.5f, 1.0f};
    linear(1, 0) = {-3.0f, 7.0f, std::numeric_limits<float>::infinity(), 0.0f};
    linear(2, 0) = {std::nanf(""), 0.0031308f, 0.214041f, 1.0f};
    linear(3, 0) = {0.0f, 0.0f, 0.0f, 0.0f};
    Image<glm::vec3> display(4, 1);
    to_display(linear.view(), display.view());
    EXPECT_EQ(display(0, 0).r, 0.0f);
    EXPECT_NEAR(display(0, 0).g, 1.0f, 1e-6f);
    EXPECT_NEAR(display(0, 0).b, 0.735357f, 1e-5f);
    EXPECT_EQ(display(1, 0).r, 0.0f);
    EXPECT_NEAR(display(1, 0).g, 1.0f, 1e-6f);
    EXPECT_NEAR(display(1, 0).b, 1.0f, 1e-6f);
    EXPECT_EQ(display(2, 0).r, 0.0f);
    EXPECT_NEAR(display(2, 0).g, 0.0031308f * 12.92f, 1e-5f);
    EXPECT_NEAR(display(2, 0).b, 0.5f, 1e-4f);
}

TEST(Metrics, PsnrOfKnownMse) {
    // Every channel off by 0.25 (exact in binary): MSE = 1/16, PSNR = 10 log10(16).
    auto a = flat(8, 6, 0.5f), b = flat(8, 6, 0.25f);
    EXPECT_DOUBLE_EQ(psnr(a.view(), b.view()), 10.0 * std::log10(16.0));
    // One channel of one pixel off by 1 in a 4x4 image: MSE = 1 / 48.
    auto c = flat(4, 4, 0.0f), d = flat(4, 4, 0.0f);
    d(2, 1).g = 1.0f;
    EXPECT_DOUBLE_EQ(psnr(c.view(), d.view()), 10.0 * std::log10(48.0));
}

TEST(Metrics, PsnrIdenticalIsInfiniteAndMaskRestricts) {
    auto a = pattern(16, 16);
    EXPECT_TRUE(std::isinf(psnr(a.view(), a.view())));
    EXPECT_GT(psnr(a.view(), a.view()), 0.0);

    // The difference lies outside the mask: identical under the mask.
    auto b = a;
    b(0, 0) = glm::vec3(1.0f);
    Image<uint8_t> mask(16, 16, 255);
    mask(0, 0) = 0;
    EXPECT_TRUE(std::isinf(psnr(a.view(), b.view(), mask.view())));
    EXPECT_FALSE(std::isinf(psnr(a.view(), b.view())));

    // Only the differing pixel counted: MSE is its own.
    Image<uint8_t> only(16, 16, 0);
    only(0, 0) = 1;
    glm::dvec3 d = glm::dvec3(a(0, 0)) - 1.0;
    double mse = (d.x * d.x + d.y * d.y + d.z * d.z) / 3.0;
    EXPECT_NEAR(psnr(a.view(), b.view(), only.view()), -10.0 * std::log10(mse), 1e-9);

    Image<uint8_t> none(16, 16, 0);
    EXPECT_TRUE(std::isnan(psnr(a.view(), b.view(), none.view())));
}

TEST(Metrics, SsimIsOneForIdenticalAndFallsWithNoise) {
    auto a = pattern(48, 40);
    EXPECT_NEAR(ssim(a.view(), a.view()), 1.0, 1e-6);
    double previous = 1.0;
    // Measured: 0.982, 0.858, 0.365, 0.063; each within 0.05 of that.
    const std::pair<float, double> expected[] = {
        {0.01f, 0.982}, {0.03f, 0.858}, {0.1f, 0.365}, {0.3f, 0.063}};
    for (auto [amplitude, near] : expected) {
        auto b = noisy(a, amplitude);
        double s = ssim(a.view(), b.view());
        EXPECT_LT(s, previous) << "amplitude " << amplitude;
        EXPECT_NEAR(s, near, 0.05) << "amplitude " << amplitude;
        previous = s;
    }
    EXPECT_LT(previous, 0.5);
}

TEST(Metrics, SsimMaskAveragesTheMapUnderTheMask) {
    // Left half identical, right half noisy: the left-half SSIM beats the whole-image SSIM.
    auto a = pattern(64, 32);
    auto b = a;
    auto n = noisy(a, 0.2f);
    for (int y = 0; y < 32; ++y)
        for (int x = 40; x < 64; ++x) b(x, y) = n(x, y);
    Image<uint8_t> left(64, 32, 0), right(64, 32, 0);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x) {
            left(x, y) = x < 24;
            right(x, y) = x >= 40;
        }
    double whole = ssim(a.view(), b.view());
    EXPECT_NEAR(ssim(a.view(), b.view(), left.view()), 1.0, 1e-5);
    EXPECT_LT(ssim(a.view(), b.view(), right.view()), whole);
    Image<uint8_t> none(64, 32, 0);
    EXPECT_TRUE(std::isnan(ssim(a.view(), b.view(), none.view())));
}

TEST(Metrics, ImageErrorCombinesAll) {
    auto a = pattern(32, 32);
    auto b = noisy(a, 0.05f);
    ImageError e = image_error(a.view(), b.view());
    EXPECT_DOUBLE_EQ(e.psnr, psnr(a.view(), b.view()));
    EXPECT_DOUBLE_EQ(e.ssim, ssim(a.view(), b.view()));
    EXPECT_DOUBLE_EQ(e.flip, flip(a.view(), b.view()));
}

TEST(Metrics, TinyImagesWork) {
    auto a = flat(1, 1, 0.5f), b = flat(1, 1, 0.25f);
    EXPECT_DOUBLE_EQ(psnr(a.view(), b.view()), 10.0 * std::log10(16.0));
    EXPECT_LT(ssim(a.view(), b.view()), 1.0);
    double f = flip(a.view(), b.view());
    EXPECT_GT(f, 0.0);
    EXPECT_LE(f, 1.0);
}

TEST(MetricsDeath, SizeMismatchIsABrokenContract) {
    auto a = flat(4, 4, 0.5f), b = flat(4, 5, 0.5f);
    EXPECT_DEATH((void)psnr(a.view(), b.view()), "assertion failed");
    EXPECT_DEATH((void)flip(a.view(), b.view()), "assertion failed");
}

TEST(Flip, IdenticalImagesGiveExactlyZero) {
    auto a = pattern(40, 30);
    Image<float> map(40, 30, -1.0f);
    EXPECT_EQ(flip(a.view(), a.view(), {}, map.view()), 0.0);
    EXPECT_EQ(map_max(map), 0.0);
}

TEST(Flip, BlackAgainstWhiteMatchesTheAnalyticValue) {
    // Flat images: the CSFs keep constants and there are no features, so FLIP is the remapped
    // colour error alone. HyAB(black, white) = 100 (L only); cmax is HyAB between Hunt-adjusted
    // green and blue, from their standard CIELAB (D65) coordinates.
    auto black = flat(24, 24, 0.0f), white = flat(24, 24, 1.0f);
    auto hunt = [](double l, double a, double b) {
        return glm::dvec3(l, 0.01 * l * a, 0.01 * l * b);
    };
    glm::dvec3 g = hunt(87.7347, -86.1827, 83.1793), b = hunt(32.3026, 79.1967, -107.8637);
    double cmax = std::pow(std::abs(g.x - b.x) + std::hypot(g.y - b.y, g.z - b.z), 0.7);
    double e = std::pow(100.0, 0.7);
    double expected = 0.95 + (e - 0.4 * cmax) / (cmax - 0.4 * cmax) * 0.05;
    Image<float> map(24, 24);
    double f = flip(black.view(), white.view(), {}, map.view());
    EXPECT_NEAR(f, expected, 2e-3);
    EXPECT_GT(f, 0.9);
    EXPECT_NEAR(map_max(map), f, 1e-4);  // uniform map
}

TEST(Flip, OneCodeValueOnGreyIsSmallButNonzero) {
    // 1/255 on mid grey shifts L* by about 0.4: 0.4^0.7 / (0.4 cmax) * 0.95 ~ 0.03.
    auto a = flat(16, 16, 0.5f), b = flat(16, 16, 0.5f + 1.0f / 255.0f);
    double f = flip(a.view(), b.view());
    EXPECT_GT(f, 0.015);
    EXPECT_LT(f, 0.05);
}

TEST(Flip, GrowsMonotonicallyWithNoise) {
    auto a = pattern(48, 48);
    double previous = 0.0;
    for (float amplitude : {0.005f, 0.02f, 0.05f, 0.1f, 0.2f, 0.4f}) {
        auto b = noisy(a, amplitude);
        double f = flip(a.view(), b.view());
        EXPECT_GT(f, previous) << "amplitude " << amplitude;
        previous = f;
    }
}

TEST(Flip, ShiftedSharpEdgeIsWorseThanShiftedGradient) {
    // Both pairs differ by the same total amount per row (1 column of 1, or 32 columns of 1/32),
    // but the moving edge is what an observer sees.
    const int w = 96, h = 32;
    auto edge = [&](int at) {
        Image<glm::vec3> img(w, h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) img(x, y) = glm::vec3(x < at ? 0.0f : 1.0f);
        return img;
    };
    auto ramp = [&](int start) {
        Image<glm::vec3> img(w, h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                img(x, y) = glm::vec3(std::clamp((x - start) / 32.0f, 0.0f, 1.0f));
        return img;
    };
    auto e0 = edge(48), e1 = edge(49), r0 = ramp(32), r1 = ramp(33);
    Image<float> edge_map(w, h), ramp_map(w, h);
    double edge_mean = flip(e0.view(), e1.view(), {}, edge_map.view());
    double ramp_mean = flip(r0.view(), r1.view(), {}, ramp_map.view());
    EXPECT_GT(map_max(edge_map), 0.6);
    EXPECT_GT(map_max(edge_map), 3.0 * map_max(ramp_map));
    EXPECT_GT(edge_mean, 0.0);
    EXPECT_GT(ramp_mean, 0.0);
}

TEST(Flip, MapStaysInUnitIntervalOnExtremeInputs) {
    std::mt19937 rng(3);
    std::uniform_int_distribution<int> bit(0, 1);
    Image<glm::vec3> a(33, 17), b(33, 17);
    for (int y = 0; y < 17; ++y)
        for (int x = 0; x < 33; ++x) {
            a(x, y) = glm::vec3(bit(rng), bit(rng), bit(rng));
            b(x, y) = glm::vec3(bit(rng), bit(rng), bit(rng));
        }
    for (float ppd : {1.0f, 10.0f, 67.0f, 200.0f}) {
        Image<float> map(33, 17, -1.0f);
        double f = flip(a.view(), b.view(), {}, map.view(), ppd);
        EXPECT_GT(f, 0.0);
        EXPECT_LE(f, 1.0);
        for (int y = 0; y < 17; ++y)
            for (int x = 0; x < 33; ++x) {
                EXPECT_GE(map(x, y), 0.0f);
                EXPECT_LE(map(x, y), 1.0f);
            }
    }
}

TEST(Flip, MaskedMeanIsTheMeanOfTheMapUnderTheMask) {
    auto a = pattern(40, 40);
    auto b = noisy(a, 0.1f);
    Image<float> map(40, 40);
    (void)flip(a.view(), b.view(), {}, map.view());
    Image<uint8_t> mask(40, 40, 0);
    double sum = 0;
    int count = 0;
    for (int y = 0; y < 40; ++y)
        for (int x = 0; x < 40; ++x)
            if ((x * 7 + y * 3) % 5 == 0) {
                mask(x, y) = 200;
                sum += map(x, y);
                ++count;
            }
    EXPECT_NEAR(flip(a.view(), b.view(), mask.view()), sum / count, 1e-9);
    Image<uint8_t> none(40, 40, 0);
    EXPECT_TRUE(std::isnan(flip(a.view(), b.view(), none.view())));
}

TEST(Flip, ErrorIsSymmetricInColorForFlatImages) {
    auto a = flat(16, 16, 0.2f), b = flat(16, 16, 0.7f);
    EXPECT_DOUBLE_EQ(flip(a.view(), b.view()), flip(b.view(), a.view()));
}

TEST(Flip, RespectsStridedViews) {
    // A view into the middle of a larger image gives the same answer as a packed copy.
    auto big_a = pattern(50, 40);
    auto big_b = noisy(big_a, 0.1f);
    ImageView<const glm::vec3> va{&big_a(5, 4), 30, 20, 50}, vb{&big_b(5, 4), 30, 20, 50};
    Image<glm::vec3> ca(30, 20), cb(30, 20);
    for (int y = 0; y < 20; ++y)
        for (int x = 0; x < 30; ++x) {
            ca(x, y) = va(x, y);
            cb(x, y) = vb(x, y);
        }
    EXPECT_DOUBLE_EQ(flip(va, vb), flip(ca.view(), cb.view()));
    EXPECT_DOUBLE_EQ(ssim(va, vb), ssim(ca.view(), cb.view()));
    EXPECT_DOUBLE_EQ(psnr(va, vb), psnr(ca.view(), cb.view()));
}
