#include <gtest/gtest.h>

#include "args.hpp"

using reprise::cli::Args;

TEST(Args, ParsesOptionsFlagsAndPositionals) {
    Args args("demo", "test");
    std::string in, out;
    int frames = 3;
    double fps = 30;
    bool verbose = false;
    args.positional("IN", &in, "input");
    args.option("--out", &out, "output");
    args.option("--frames", &frames, "n");
    args.option("--fps", &fps, "rate");
    args.flag("--verbose", &verbose, "talk");
    const char* argv[] = {"a.exr", "--out", "dir", "--frames=12", "--fps", "59.94", "--verbose"};
    ASSERT_TRUE(args.parse(7, const_cast<char**>(argv)).ok());
    EXPECT_EQ(in, "a.exr");
    EXPECT_EQ(out, "dir");
    EXPECT_EQ(frames, 12);
    EXPECT_DOUBLE_EQ(fps, 59.94);
    EXPECT_TRUE(verbose);
    EXPECT_TRUE(args.given("--fps"));
}

TEST(Args, RejectsBadArgumentsWithTheirName) {
    int frames = 0;
    Args args("demo", "test");
    args.option("--frames", &frames, "n");
    const char* bad_int[] = {"--frames", "12x"};
    auto status = args.parse(2, const_cast<char**>(bad_int));
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("--frames"), std::string::npos);
    const char* unknown[] = {"--nope"};
    EXPECT_FALSE(args.parse(1, const_cast<char**>(unknown)).ok());
    const char* missing[] = {"--frames"};
    EXPECT_FALSE(args.parse(1, const_cast<char**>(missing)).ok());
}

TEST(Args, ParsesSizesWithinLimits) {
    int w = 0, h = 0;
    EXPECT_TRUE(reprise::cli::parse_size("1920x1080", w, h).ok());
    EXPECT_EQ(w, 1920);
    EXPECT_EQ(h, 1080);
    EXPECT_FALSE(reprise::cli::parse_size("0x10", w, h).ok());
    EXPECT_FALSE(reprise::cli::parse_size("16385x2", w, h).ok());
    EXPECT_FALSE(reprise::cli::parse_size("12", w, h).ok());
    EXPECT_FALSE(reprise::cli::parse_size("-4x4", w, h).ok());
}
