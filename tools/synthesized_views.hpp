#pragma once
// The views a client makes from decoded depth (issue 18 §6): each decoded frame extrapolated 1, 2
// and 3 display periods ahead at four times the frame rate (120 Hz from 30 Hz) and turned into
// the other eye 64 mm to the right, once with the decoded depth and motion and once with the
// rendered ones (both from the decoded colour), each scored against the scene rendered there.
#include <array>
#include <string>

#include "reprise/core/frame.hpp"
#include "reprise/core/metrics.hpp"
#include "reprise/server/renderer.hpp"

namespace reprise::cli {

struct SynthesizedViews {
    static constexpr int kViews = 4;  // +1/4, +2/4, +3/4 of a frame period; the other eye
    static const char* name(int view);
    std::array<double, kViews> decoded_psnr{}, rendered_psnr{};  // sums over frames
    int frames = 0;
    // Mean PSNR of the views from decoded depth minus those from rendered depth (dB).
    double loss_db(int view) const { return (decoded_psnr[view] - rendered_psnr[view]) / frames; }
};

class SynthesizedViewScorer {
public:
    SynthesizedViewScorer(server::Renderer& renderer, const server::Scene& scene,
                          const server::CameraPath& path, double fps);
    // Adds frame `index` of the sequence: `rendered` as the renderer made it, `decoded` as the
    // client got it.
    Status add(int index, const Frame& rendered, const GBufferView& decoded,
               SynthesizedViews& views);

private:
    server::Renderer& renderer_;
    const server::Scene& scene_;
    const server::CameraPath& path_;
    double fps_;
    Frame truth_, lossless_, warped_;
};

}  // namespace reprise::cli
