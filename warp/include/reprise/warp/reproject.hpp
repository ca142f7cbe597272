#pragma once
// Reverse reprojection (Nehab et al. 2007): each pixel of the current frame fetches what the
// previous frame computed at p + motion, if the same surface was visible there.
#include <cstddef>
#include <cstdint>

#include "reprise/core/frame.hpp"
#include "reprise/core/gbuffer.hpp"

namespace reprise::warp {

// An interleaved float payload of any number of channels (colour, shading terms, history).
struct Payload {
    float* data = nullptr;
    int width = 0;
    int height = 0;
    int channels = 0;
    std::ptrdiff_t stride = 0;  // floats between rows
    float* pixel(int x, int y) const { return data + y * stride + std::ptrdiff_t(x) * channels; }
};
struct ConstPayload {
    const float* data = nullptr;
    int width = 0;
    int height = 0;
    int channels = 0;
    std::ptrdiff_t stride = 0;
    const float* pixel(int x, int y) const {
        return data + y * stride + std::ptrdiff_t(x) * channels;
    }
};
ConstPayload payload_of(ImageView<const glm::vec4> rgba);
Payload payload_of(ImageView<glm::vec4> rgba);

struct ReprojectOptions {
    // Hit when |z_expected - z_previous| <= depth_tolerance * z_expected, where z_previous is the
    // bilinearly reconstructed previous depth and z_expected the depth this pixel's surface point
    // has in the previous camera.
    float depth_tolerance = 0.02f;
    bool match_ids = true;  // when both frames have ids, all four taps must carry this pixel's id
    // z_expected assumes a static world (current camera -> world -> previous camera), which is
    // wrong for animated objects. Where ids are matched and all four taps agree, this looser
    // tolerance applies instead: the id carries moving objects, the depth test still rejects
    // self-occlusion by far-away parts of the same object.
    float id_depth_tolerance = 0.2f;
    // Background (depth +inf, id 0) hits where all four previous taps are background too; its
    // motion is that of the point at infinity. When false, background pixels count as invalid.
    bool background = true;
    // Only every step-th pixel of every step-th row (x and y multiples of step) is looked up;
    // the others keep their `out` and `hit`, and the counts are of the looked-up pixels. A cheap
    // survey, e.g. for a shot-change test.
    int step = 1;
};

// The per-frame constants of reproject, shared by the CPU and GPU paths so both decide alike.
// The depth the surface point seen at pixel position (px, py) with current depth z has in the
// previous camera is affine in (px w, py w, z, 1), with w the current clip w (z for perspective,
// 1 for orthographic): z_expected = w (kx px + ky py + kw) + kz z + k1, w = wz z + w1. All NaN
// for a projection reproject cannot invert (every non-background pixel is then invalid).
struct ReprojectSetup {
    float kx, ky, kw, kz, k1;
    float wz, w1;
    float px0, py0;  // pixel x is seen at px = x + px0 (centre + jitter)
    float qx0, qy0;  // and looked up in the previous image at x + qx0 + motion.x
    float tolerance, id_tolerance;
    bool use_ids, background;
};
// `width` x `height`: the current frame; `ids`: both frames carry object ids.
ReprojectSetup reproject_setup(const Camera& current, const Camera& previous, int width, int height,
                               bool ids, const ReprojectOptions& options);

struct ReprojectCounts {
    std::size_t hits = 0;
    std::size_t offscreen = 0;  // p + motion outside the previous image
    std::size_t behind = 0;     // the point was behind the previous camera (w <= 0)
    std::size_t occluded = 0;   // depth test failed
    std::size_t other_id = 0;   // id test failed
    std::size_t invalid = 0;    // NaN/Inf in motion, depth or the fetched payload
    std::size_t misses() const { return offscreen + behind + occluded + other_id + invalid; }
    bool operator==(const ReprojectCounts&) const = default;
};

// For each pixel p of `current`: on a hit, out(p) = previous payload at p + motion (bilinear) and
// hit(p) = 1; on a miss out(p) is left as it was and hit(p) = 0. `previous` supplies the depth and
// ids of the payload's frame; `hit` may be empty; `out` must not overlap the previous payload.
// Threaded; allocates nothing.
// With jitter the lookup is p + 0.5 + jitter + motion - previous jitter (the payload's samples lie
// at its own jittered positions). Taps of zero bilinear weight are ignored, so integer motion
// copies exactly. A camera whose projection is neither perspective nor orthographic (last row
// with x/y terms) or not invertible makes every non-background pixel invalid.
ReprojectCounts reproject(const GBufferView& current, const GBufferView& previous,
                          ConstPayload previous_payload, Payload out, ImageView<uint8_t> hit,
                          const ReprojectOptions& options = {});
// The scalar single-threaded reference of the same function (tests compare the two).
ReprojectCounts reproject_reference(const GBufferView& current, const GBufferView& previous,
                                    ConstPayload previous_payload, Payload out,
                                    ImageView<uint8_t> hit, const ReprojectOptions& options = {});

// Which pixels are recomputed this frame although the cache could serve them (Nehab §5).
// Every policy refreshes each pixel exactly once per n frames.
enum class Refresh {
    None,
    Tiled,        // a grid of n tiles, as square as n's divisors allow; tile (t mod n) refreshes
    Random2x2,    // 2x2 blocks, each with a fixed random phase i: refresh when (t + i) mod n = 0;
                  // stratified: each run of n blocks in raster order holds every phase once
    Interleaved,  // pixel (x, y) has phase i = (x + y * width) mod n, refreshing like Random2x2
};
// 1 where pixel (x, y) refreshes at frame t under `policy` with period n (n >= 1), else 0.
void refresh_mask(Refresh policy, int n, int64_t t, ImageView<uint8_t> mask, uint32_t seed = 1);

// Amortized sampling (Nehab §6): f_t = alpha * s_t + (1 - alpha) * f_{t-1}(reprojected), per pixel.
// Where `hit` is 0 (an empty `hit` counts as all 1) or the history is not finite, the history
// restarts: f_t = s_t. `alpha` may be a single value (alpha_map empty); alphas are clamped to
// [0, 1], NaN counts as 1. A constant signal stays exactly constant for any alpha, and results
// below FLT_MIN are flushed to 0 (no denormals). The stationary variance of white noise drops by
// alpha / (2 - alpha). `out` may alias either input.
void accumulate(ConstPayload sample, ConstPayload reprojected_history, ImageView<const uint8_t> hit,
                float alpha, ImageView<const float> alpha_map, Payload out);

}  // namespace reprise::warp
