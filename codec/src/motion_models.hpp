#pragma once
// Motion coded within a bound (motion_models.cpp): affine models per quadtree node, merged from
// neighbours, pixel values only where no model fits.
#include <cstdint>
#include <span>
#include <vector>

#include "object_motion.hpp"
#include "reprise/core/image.hpp"
#include "reprise/core/status.hpp"
#include "slices.hpp"

namespace reprise::codec {

struct SequenceParams;
struct StreamStats;

// Residual motion over the camera motion, in 1/512 px: value at the origin pixel plus a change
// per pixel in x and in y; or (object >= 0) the motion of that rigid object.
struct MotionModel {
    int object = -1;
    int64_t ax = 0, ay = 0;
    int64_t gxx = 0, gxy = 0, gyx = 0, gyy = 0;
    int x0 = 0, y0 = 0;
    int64_t value_x(int x, int y) const { return ax + gxx * (x - x0) + gxy * (y - y0); }
    int64_t value_y(int x, int y) const { return ay + gyx * (x - x0) + gyy * (y - y0); }
};

struct MotionCell {  // one 4x4 cell: what its neighbours predict from
    MotionModel model;
    bool has_model = false;
    bool zero = true;
};

struct MotionModelScratch {
    std::vector<MotionCell> cells;
    int cell_columns = 0;
    std::vector<uint8_t> kinds;      // per pixel: camera motion, a model, its own value
    std::vector<uint8_t> which;      // per pixel of a 4x4 cell coded pixel by pixel: its model
    std::vector<glm::ivec2> values;  // per pixel: the decoded residual, 1/512 px (clamped)
    std::vector<uint8_t> edges;      // per 4x4 cell: a step in decoded depth within it
};

// Whether every pixel of row y is within `bound` px of the camera motion (NaN both ways counts).
bool motion_within_bound(ImageView<const glm::vec2> source, ImageView<const glm::vec2> base, int y,
                         float bound);

// The objects' `fields` (object_motion.hpp) are what object models refer to; `ids` (the
// encoder's object ids) chooses which one to try (a field with id 0, the cameras' motion, for
// ids that are no field's). `predicted` (may be empty): the object a pixel's base moves with.
// `owner` (when not empty) gets each pixel's object id where an object model or the base gave
// its motion, else 0. `carry`: the slices' models (version 20).
void encode_motion_models(const SequenceParams& sp, ImageView<const float> depth,
                          ImageView<const glm::vec2> base, ImageView<const glm::vec2> source,
                          ImageView<const uint32_t> ids, std::span<const ObjectField> fields,
                          ImageView<const uint32_t> predicted, ImageView<glm::vec2> out,
                          ImageView<uint32_t> owner, MotionModelScratch& scratch,
                          const ModelCarry& carry, std::vector<std::vector<uint8_t>>& slice_bytes,
                          std::vector<uint8_t>& bytes, StreamStats& stats);
Status decode_motion_models(const SequenceParams& sp, ImageView<const float> depth,
                            ImageView<const glm::vec2> base, std::span<const ObjectField> fields,
                            ImageView<const uint32_t> predicted,
                            const std::vector<std::span<const uint8_t>>& slices,
                            ImageView<glm::vec2> out, ImageView<uint32_t> owner,
                            MotionModelScratch& scratch, const ModelCarry& carry,
                            StreamStats& stats);

}  // namespace reprise::codec
