#pragma once
// 8-bit RGB pictures of G-buffer channels for people to look at (export, reports).
#include <cstdint>
#include <glm/ext/vector_uint3_sized.hpp>
#include <span>
#include <string>

#include "reprise/core/image.hpp"

namespace reprise {

using Rgb8 = glm::u8vec3;

// Linear colour -> sRGB display values, rounded to 8 bits (NaN -> 0).
void visualize_color(ImageView<const glm::vec4> linear, ImageView<Rgb8> out);

// Depth range shown by visualize_depth; near = far = 0 means the image's own range.
struct DepthRange {
    float near = 0.0f;
    float far = 0.0f;
};
// The smallest and largest finite positive depth; {0, 0} when there is none.
DepthRange depth_range(ImageView<const float> depth);
// Grey on a log scale: near is white, far is dark grey; background (+inf, NaN, <= 0) is black.
void visualize_depth(ImageView<const float> depth, ImageView<Rgb8> out, DepthRange range = {});

// The `quantile` (0..1; 1 = the largest) of the finite nonzero motion lengths, in pixels;
// 0 when nothing moves. A quantile below 1 keeps a few outliers from washing out the rest.
float motion_length(ImageView<const glm::vec2> motion, float quantile = 1.0f);
// Flow wheel: hue = direction, saturation = length / saturate_at (clamped), zero motion white,
// NaN black. saturate_at <= 0 means the largest motion_length of this image.
void visualize_motion(ImageView<const glm::vec2> motion, ImageView<Rgb8> out,
                      float saturate_at = 0.0f);

// n * 0.5 + 0.5; zero-length or NaN normals (background) are black.
void visualize_normal(ImageView<const glm::vec3> normal, ImageView<Rgb8> out);

// A stable hashed colour per id; id 0 (background) is black.
void visualize_id(ImageView<const uint32_t> id, ImageView<Rgb8> out);
Rgb8 id_color(uint32_t id);

struct Tile {
    ImageView<const Rgb8> image;  // empty: a black tile
    std::string label;
};

struct SheetOptions {
    int columns = 3;
    int tile_width = 0;     // tiles are scaled to this width; 0 = the widest tile's width
    int gap = 4;            // pixels between and around tiles
    int label_height = 20;  // strip above each tile for its label; 0 = no labels
};

// Tiles in rows of `columns`, each under its label, on a dark background.
Image<Rgb8> contact_sheet(std::span<const Tile> tiles, const SheetOptions& options = {});

// Writes an 8-bit RGB image as PNG (or any format OpenCV knows from the extension).
Status write_png(const std::string& path, ImageView<const Rgb8> image);

}  // namespace reprise
