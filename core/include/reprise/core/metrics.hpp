#pragma once
// Image error on display values (sRGB-encoded after clamping linear light to [0, 1]).
#include <cstdint>

#include "reprise/core/image.hpp"
#include "reprise/core/status.hpp"

namespace reprise {

// Display RGB in [0, 1] from linear RGBA (alpha ignored).
void to_display(ImageView<const glm::vec4> linear, ImageView<glm::vec3> display);

struct ImageError {
    double psnr = 0.0;  // dB over RGB, +inf for identical images
    double ssim = 0.0;  // mean SSIM over RGB (OpenCV quality), 1 for identical images
    double flip = 0.0;  // mean LDR-FLIP, 0 for identical images
};

// All three metrics between two display images of the same size (a size mismatch is a broken
// contract). A non-empty `mask` (nonzero = counted, same size) restricts the means to its
// pixels; a mask that selects no pixel gives NaN.
ImageError image_error(ImageView<const glm::vec3> reference, ImageView<const glm::vec3> test,
                       ImageView<const uint8_t> mask = {});

double psnr(ImageView<const glm::vec3> reference, ImageView<const glm::vec3> test,
            ImageView<const uint8_t> mask = {});
double ssim(ImageView<const glm::vec3> reference, ImageView<const glm::vec3> test,
            ImageView<const uint8_t> mask = {});
// FLIP's viewing condition, pixels per degree, must be in (0, kMaxFlipPpd]: its filters grow
// with it (about 0.2 * ppd pixels each side).
inline constexpr double kMaxFlipPpd = 10000.0;
Status check_flip_ppd(double pixels_per_degree);
// What flip() allocates for a width x height image at this ppd (within kMaxFlipPpd), estimated.
std::uint64_t flip_memory(int width, int height, double pixels_per_degree);
// check_flip_ppd, then flip_memory against the memory limit (reprise/core/memory_limit.hpp):
// the check for a ppd or a size from outside, before flip().
Status check_flip(int width, int height, double pixels_per_degree);
// Per-pixel LDR-FLIP error (Andersson et al. 2020, 67 pixels per degree by default) into
// `error_map` when it is not empty; returns the mean over the mask. A ppd that check_flip_ppd
// refuses is a broken contract.
double flip(ImageView<const glm::vec3> reference, ImageView<const glm::vec3> test,
            ImageView<const uint8_t> mask = {}, ImageView<float> error_map = {},
            float pixels_per_degree = 67.0f);

}  // namespace reprise
