// The owning image: sizes, copies and moves.
#include <gtest/gtest.h>

#include <utility>

#include "reprise/core/image.hpp"

namespace reprise {
namespace {

// A moved-from image used to keep its size with no pixels, so resizing it to that size kept
// zero pixels and the next write ran off the end (bench stream reused a moved-from depth).
TEST(Image, MovedFromIsEmptyAndResizesAgain) {
    Image<float> a(4, 3, 2.0f);
    Image<float> b(std::move(a));
    EXPECT_EQ(b.width(), 4);
    EXPECT_EQ(b.pixel_count(), 12u);
    EXPECT_EQ(a.width(), 0);  // NOLINT(bugprone-use-after-move): the state is the contract
    EXPECT_EQ(a.height(), 0);
    EXPECT_TRUE(a.empty());
    a.resize(4, 3);
    ASSERT_EQ(a.pixel_count(), 12u);
    a(3, 2) = 1.0f;

    Image<float> c(2, 2, 5.0f);
    c = std::move(b);
    EXPECT_EQ(c.width(), 4);
    EXPECT_EQ(c(0, 0), 2.0f);
    EXPECT_EQ(b.width(), 0);  // NOLINT(bugprone-use-after-move)
    EXPECT_EQ(b.pixel_count(), 0u);
    b.resize(4, 3);
    EXPECT_EQ(b.pixel_count(), 12u);

    const Image<float> d = c;  // copies keep both
    EXPECT_EQ(d.pixel_count(), 12u);
    EXPECT_EQ(c.pixel_count(), 12u);
}

}  // namespace
}  // namespace reprise
