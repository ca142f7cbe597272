// Rigid object motion in the codec: the fit against the renderer's own motion, what it saves in a
// stream, encoder/decoder agreement, and object lists that must be refused.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "../codec/src/internal.hpp"
#include "../codec/src/object_motion.hpp"
#include "reprise/codec/codec.hpp"
#include "support/codec.hpp"
#include "support/frames.hpp"
#include "support/renderer.hpp"

using namespace reprise;
using namespace reprise::codec;
using test::decode_all;

namespace {

std::vector<Frame> render(const std::string& scene, int frames, int w, int h) {
    return test::render_scene(scene, frames, w, h, 30.0, 0);
}

std::vector<ObjectMotion> fit(const Frame& f, Image<glm::vec2>& base) {
    base.resize(f.depth.width(), f.depth.height());
    camera_motion(f.camera, f.depth.view(), f.camera.prev_view, f.camera.prev_projection,
                  base.view());
    return fit_object_motions(f.camera, f.depth.view(), f.id.view(), f.motion.view(), base.view(),
                              0.25f, {});
}

// The decoder gives the encoder's motion, depth and colour bit for bit, and every decoded pixel's
// motion lies within 0.25 px of the renderer's.
void expect_decoded_as_encoded(const std::vector<Frame>& frames, const test::Coded& coded) {
    const auto decoded = decode_all(coded.packets);
    ASSERT_EQ(decoded.size(), frames.size());
    for (std::size_t i = 0; i < frames.size(); ++i) {
        EXPECT_TRUE(test::same_bits(decoded[i].motion, coded.reconstructions[i].motion));
        EXPECT_TRUE(test::same_bits(decoded[i].depth, coded.reconstructions[i].depth));
        EXPECT_TRUE(test::same_bits(decoded[i].color, coded.reconstructions[i].color));
        for (std::size_t p = 0; p < frames[i].motion.pixel_count(); ++p)
            ASSERT_LE(glm::length(decoded[i].motion.data()[p] - frames[i].motion.data()[p]), 0.25f)
                << "frame " << i << " pixel " << p;
    }
}

}  // namespace

// On rendered depth, each fitted object's motion field matches the renderer's motion of its
// pixels to within 0.01 px (rigid objects: the cars of `crossing`, the ball of `fast`).
TEST(ObjectMotion, TheFitGivesTheRenderersMotionOfRigidObjects) {
    for (const char* scene : {"crossing", "fast"}) {
        SCOPED_TRACE(scene);
        const auto frames = render(scene, 3, 320, 180);
        Image<glm::vec2> base;
        std::size_t objects = 0;
        for (std::size_t i = 1; i < frames.size(); ++i) {
            const Frame& f = frames[i];
            const std::vector<ObjectMotion> found = fit(f, base);
            std::vector<ObjectField> fields;
            object_fields(f.camera, f.depth.view(), found, fields);
            for (std::size_t k = 0; k < found.size(); ++k) {
                std::size_t pixels = 0, close = 0;
                for (int y = 0; y < f.id.height(); ++y)
                    for (int x = 0; x < f.id.width(); ++x) {
                        if (f.id(x, y) != found[k].id) continue;
                        ++pixels;
                        close += glm::length(fields[k].at(x, y) - f.motion(x, y)) <= 0.01f;
                    }
                EXPECT_GE(double(close), 0.99 * double(pixels))
                    << "frame " << i << " object " << found[k].id;
            }
            objects += found.size();
        }
        EXPECT_GE(objects, 2u);
    }
}

// A static scene has no object of its own motion; neither has a frame without ids.
TEST(ObjectMotion, NothingMovesOnItsOwnInPan) {
    const auto frames = render("pan", 2, 160, 96);
    Image<glm::vec2> base;
    EXPECT_TRUE(fit(frames[1], base).empty());
    Frame no_ids = frames[1];
    no_ids.id = {};
    EXPECT_TRUE(fit(no_ids, base).empty());
}

// With lossless depth the objects carry their pixels' motion: crossing's motion bits fall to
// 0.7 of the affine models' alone (measured at 320x180, 5 frames: 0.645), every pixel still
// within the bound, the decoder bit-identical to the encoder.
TEST(ObjectMotion, ObjectsCutTheMotionBitsOfCrossing) {
    const auto frames = render("crossing", 5, 320, 180);
    std::size_t bits[2] = {0, 0};
    for (bool objects : {false, true}) {
        const test::Coded coded =
            test::encode_all(frames, {.depth = DepthMode::Lossless, .rigid_objects = objects});
        bits[objects] = coded.stats.motion_bits;
        EXPECT_EQ(coded.stats.motion_objects > 0, objects);
        expect_decoded_as_encoded(frames, coded);
    }
    EXPECT_LE(double(bits[1]), 0.7 * double(bits[0])) << bits[1] << " against " << bits[0];
}

// The default stream (view depth): the objects' depth follows them and their travel sets the
// view step; all bits of crossing at most 0.99 of the stream without objects (measured at
// 320x180, 5 frames: 0.984; 640x360, 8 frames: 0.972).
TEST(ObjectMotion, TheDefaultStreamOfCrossingIsSmallerWithObjects) {
    const auto frames = render("crossing", 5, 320, 180);
    std::size_t bits[2] = {0, 0};
    for (bool objects : {false, true}) {
        const test::Coded coded =
            test::encode_all(frames, {.depth = DepthMode::View, .rigid_objects = objects});
        bits[objects] = coded.stats.total_bits();
        const auto decoded = decode_all(coded.packets);
        ASSERT_EQ(decoded.size(), frames.size());
        for (std::size_t i = 0; i < frames.size(); ++i)
            EXPECT_TRUE(test::same_bits(decoded[i].depth, coded.reconstructions[i].depth));
    }
    EXPECT_LE(double(bits[1]), 0.99 * double(bits[0])) << bits[1] << " against " << bits[0];
}

// Each pixel's object predicted from the reference (the object it moved with there, at the depth
// its motion gives): pixels that moved as predicted cost no motion bits, silhouettes included.
// Measured at 160x96, 5 frames, motion bits of frames 1-4 (the object lists included): courtyard
// 3224 (5648 without the prediction), crossing 2032 (3552); since version 20, where the quadtree
// and the pixels' flags know the steps in decoded depth and the edges between predicted owners,
// 2920 and 1608. Every decoded pixel within the bound, the decoder bit-identical to the encoder.
TEST(ObjectMotion, PixelsPredictedToMoveWithTheirObjectCostNoMotionBits) {
    for (auto [scene, most] : {std::pair{"courtyard", 3150}, std::pair{"crossing", 1800}}) {
        SCOPED_TRACE(scene);
        const auto frames = render(scene, 5, 160, 96);
        const test::Coded key = test::encode_all({frames[0]}, {.qp = 34});
        const test::Coded coded = test::encode_all(frames, {.qp = 34});
        EXPECT_LE(coded.stats.motion_bits - key.stats.motion_bits, std::size_t(most));
        expect_decoded_as_encoded(frames, coded);
    }
}

// The list as the camera section carries it: raw, or against the reference's objects, where an
// object that kept its motion costs a byte per float.
TEST(ObjectMotion, ListsRoundTripAndUnchangedMotionCostsLittle) {
    ObjectMotion a{.x0 = 3, .y0 = 4, .x1 = 40, .y1 = 30, .id = 7};
    a.rotation[0] = 0.01f, a.rotation[2] = -0.2f, a.translation[1] = 0.5f;
    ObjectMotion b{.x0 = 0, .y0 = 0, .x1 = 64, .y1 = 48, .id = 9};
    b.translation[0] = -1.0f;
    const std::vector<ObjectMotion> reference{a};
    ObjectMotion moved = a;
    moved.x0 += 2, moved.x1 += 2;
    const std::vector<ObjectMotion> objects{moved, b};
    for (const std::vector<ObjectMotion>* ref :
         {(const std::vector<ObjectMotion>*)nullptr, &reference}) {
        std::vector<uint8_t> bytes;
        ByteWriter w(bytes);
        write_objects(objects, ref, w);
        ByteReader r(bytes, "objects");
        std::vector<ObjectMotion> back;
        ASSERT_TRUE(read_objects(r, 64, 48, ref, back).ok());
        EXPECT_EQ(r.remaining(), 0u);
        ASSERT_EQ(back.size(), 2u);
        for (std::size_t k = 0; k < 2; ++k) {
            EXPECT_EQ(back[k].id, objects[k].id);
            EXPECT_EQ(back[k].x0, objects[k].x0);
            EXPECT_EQ(back[k].y1, objects[k].y1);
            EXPECT_EQ(back[k].matrix(), objects[k].matrix());
        }
        // count, then per object: id, 4 box varints, 6 floats (raw 24 bytes, unchanged 6).
        EXPECT_EQ(bytes.size(), ref ? 1u + (1 + 4 + 6) + (1 + 4 + 24) : 1u + (1 + 4 + 24) * 2);
    }
}

TEST(ObjectMotion, HostileListsAreRefusedWithTheirReason) {
    auto parse = [](const std::vector<ObjectMotion>& objects, int count_override = -1) {
        std::vector<uint8_t> bytes;
        ByteWriter w(bytes);
        write_objects(objects, nullptr, w);
        if (count_override >= 0) bytes[0] = uint8_t(count_override);
        ByteReader r(bytes, "objects");
        std::vector<ObjectMotion> back;
        return read_objects(r, 64, 48, nullptr, back);
    };
    const ObjectMotion good{.x0 = 0, .y0 = 0, .x1 = 8, .y1 = 8, .id = 1};
    EXPECT_TRUE(parse({good}).ok());
    EXPECT_NE(parse({good}, 0).message().find("0 objects"), std::string::npos);
    EXPECT_NE(parse({good}, 33).message().find("33 objects"), std::string::npos);
    EXPECT_NE(parse({good}, 2).message().find("truncated"), std::string::npos);
    ObjectMotion o = good;
    o.x1 = 65;
    EXPECT_NE(parse({o}).message().find("outside the picture"), std::string::npos);
    o = good;
    o.id = 0;
    EXPECT_NE(parse({o}).message().find("id 0"), std::string::npos);
    o = good;
    o.rotation[0] = 0.9f, o.rotation[1] = 0.9f;
    EXPECT_NE(parse({o}).message().find("not a rotation"), std::string::npos);
    o = good;
    o.translation[2] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_NE(parse({o}).message().find("translation"), std::string::npos);
    std::vector<ObjectMotion> many(5, ObjectMotion{.x0 = 0, .y0 = 0, .x1 = 64, .y1 = 48, .id = 1});
    EXPECT_NE(parse(many).message().find("more than 4 pictures"), std::string::npos);
}
