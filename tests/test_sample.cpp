#include <gtest/gtest.h>

#include <limits>

#include "reprise/warp/sample.hpp"

using namespace reprise;
using namespace reprise::warp;

TEST(Sample, BilinearAndBicubicInterpolatePixelCentresAndLinearRamps) {
    Image<float> ramp(9, 7);
    for (int y = 0; y < 7; ++y)
        for (int x = 0; x < 9; ++x) ramp(x, y) = 3.0f * x - 2.0f * y + 1.0f;
    ImageView<const float> v = ramp.view();
    for (float y = 1.5f; y <= 5.5f; y += 0.25f)
        for (float x = 1.5f; x <= 7.5f; x += 0.25f) {
            float expected = 3.0f * (x - 0.5f) - 2.0f * (y - 0.5f) + 1.0f;
            Bilinear b = bilinear_taps(x, y, 9, 7);
            ASSERT_TRUE(b.inside);
            EXPECT_NEAR(bilinear_fetch(v, b), expected, 1e-4f);
            EXPECT_NEAR(bicubic_fetch(v, x, y), expected, 1e-4f);
        }
    EXPECT_EQ(bicubic_fetch(v, 4.5f, 3.5f), ramp(4, 3));
}

TEST(Sample, PositionsOutsideOrNotFiniteAreNotInside) {
    for (float bad : {-0.01f, 9.01f, 1e30f, -1e30f, std::numeric_limits<float>::quiet_NaN(),
                      std::numeric_limits<float>::infinity()})
        EXPECT_FALSE(bilinear_taps(bad, 3.0f, 9, 7).inside) << bad;
    Bilinear edge = bilinear_taps(0.0f, 7.0f, 9, 7);  // the image's corner: taps clamp
    EXPECT_TRUE(edge.inside);
    EXPECT_EQ(edge.x0, 0);
    EXPECT_EQ(edge.y1, 6);
}
