#pragma once
// Spatio-temporal upsampling (Herzog et al. 2010) on the GPU: warp::SpatioTemporalUpsampler's
// passes as OpenGL ES compute shaders, its history kept in textures between frames.
#include <memory>

#include "reprise/gpu/context.hpp"
#include "reprise/warp/upsample.hpp"

namespace reprise::gpu {

class Upsampler final : public warp::UpsampleBackend {
public:
    // `context` must outlive the upsampler; its programs are linked here, once.
    static Status create(Context& context, const warp::UpsampleOptions& options,
                         std::unique_ptr<Upsampler>& upsampler);
    ~Upsampler();
    Upsampler(const Upsampler&) = delete;
    Upsampler& operator=(const Upsampler&) = delete;

    // warp::SpatioTemporalUpsampler::upsample: the same inputs, output and stats (the guides'
    // NaN/Inf repaired on the CPU first); an error instead of an assertion for sizes and options
    // it cannot take, and for a full camera whose projection is skewed (with history).
    Status upsample(ImageView<const glm::vec4> low_color, glm::vec2 jitter_px,
                    const GBufferView& full, ImageView<glm::vec4> out,
                    warp::UpsampleStats* stats = nullptr) override;
    // The same on textures: `low_color` GL_RGBA32F of low_width x low_height, the full G-buffer's
    // depth (motion GL_RG32F and id GL_R32UI where non-zero), `normal` GL_RGB32F (0: none),
    // `out` GL_RGBA32F of the full size. No repair here: NaN/Inf guides are the caller's to avoid.
    Status upsample(unsigned low_color, int low_width, int low_height, glm::vec2 jitter_px,
                    const GBufferTextures& full, unsigned normal, unsigned out,
                    warp::UpsampleStats* stats = nullptr);
    void reset() override;  // forgets the history (a cut, a new stream)

    // The CPU-image upsample() leaves `out` unwritten and keeps the result in a texture: a
    // gpu::FrucBackend on the same context joined by inputs_from() extrapolates a frame whose
    // colour is that `out` (the same pixels, size and stride) from the texture, nothing
    // downloaded or uploaded; download_kept() writes it for a reader on the CPU. Until the next
    // call; a failed call and reset() keep nothing. Off by default; the time of download_kept
    // counts in total().download_ms.
    void keep_output(bool keep);
    bool output_kept() const override;
    Status download_kept(ImageView<glm::vec4> out) override;
    // The texture (GL_RGBA32F) kept for `out`, or 0 when the last call kept nothing for it.
    unsigned kept_for(ImageView<const glm::vec4> out) const;
    // What of `frame` is on the GPU here: its colour where it is the kept output (kept_for), its
    // depth and motion (repaired) where they are those the last CPU-image upsample() was guided
    // by (the same pixels, size and stride; until the next call or reset()). Images are known
    // by their address: a caller that reuses them for frames not upsampled here resets the
    // upsampler first (the streaming client does after each full-resolution frame).
    FrameOnGpu on_gpu(const GBufferView& frame) const;

    const Context& context() const;
    const Timings& timings() const;  // the last call's
    const Timings& total() const;    // every call's, summed, and how many
    std::size_t frames() const;

    struct State;

private:
    Upsampler();
    std::unique_ptr<State> state_;
};

}  // namespace reprise::gpu
