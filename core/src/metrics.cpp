#include "reprise/core/metrics.hpp"

#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/quality/qualityssim.hpp>

#include "reprise/core/frame.hpp"

namespace reprise {

namespace {

cv::Mat wrap(ImageView<const glm::vec3> view) {
    return cv::Mat(view.height, view.width, CV_32FC3, const_cast<glm::vec3*>(view.data),
                   std::size_t(view.stride) * sizeof(glm::vec3));
}

void check_sizes(ImageView<const glm::vec3> reference, ImageView<const glm::vec3> test,
                 ImageView<const uint8_t> mask) {
    REPRISE_ASSERT(reference.width == test.width && reference.height == test.height);
    REPRISE_ASSERT(mask.empty() ||
                   (mask.width == reference.width && mask.height == reference.height));
}

bool counted(ImageView<const uint8_t> mask, int x, int y) {
    return mask.empty() || mask(x, y) != 0;
}

}  // namespace

void to_display(ImageView<const glm::vec4> linear, ImageView<glm::vec3> display) {
    REPRISE_ASSERT(linear.width == display.width && linear.height == display.height);
    for (int y = 0; y < linear.height; ++y) {
        const glm::vec4* in = linear.row(y);
        glm::vec3* out = display.row(y);
        for (int x = 0; x < linear.width; ++x)
            out[x] = {linear_to_srgb(in[x].r), linear_to_srgb(in[x].g), linear_to_srgb(in[x].b)};
    }
}

double psnr(ImageView<const glm::vec3> reference, ImageView<const glm::vec3> test,
            ImageView<const uint8_t> mask) {
    check_sizes(reference, test, mask);
    double sum = 0.0;
    std::size_t count = 0;
    for (int y = 0; y < reference.height; ++y) {
        for (int x = 0; x < reference.width; ++x) {
            if (!counted(mask, x, y)) continue;
            glm::dvec3 d = glm::dvec3(reference(x, y)) - glm::dvec3(test(x, y));
            sum += d.x * d.x + d.y * d.y + d.z * d.z;
            ++count;
        }
    }
    if (count == 0) return std::numeric_limits<double>::quiet_NaN();
    double mse = sum / (3.0 * double(count));
    if (mse == 0.0) return std::numeric_limits<double>::infinity();
    return -10.0 * std::log10(mse);
}

double ssim(ImageView<const glm::vec3> reference, ImageView<const glm::vec3> test,
            ImageView<const uint8_t> mask) {
    check_sizes(reference, test, mask);
    if (reference.empty()) return std::numeric_limits<double>::quiet_NaN();
    // OpenCV's SSIM constants assume the 8-bit range, so the [0, 1] values are scaled by 255.
    cv::Mat ref, cmp;
    wrap(reference).convertTo(ref, CV_32FC3, 255.0);
    wrap(test).convertTo(cmp, CV_32FC3, 255.0);
    cv::Mat map;
    cv::Scalar mean = cv::quality::QualitySSIM::compute(ref, cmp, map);
    if (mask.empty()) return (mean[0] + mean[1] + mean[2]) / 3.0;

    cv::Mat map32;
    map.convertTo(map32, CV_32FC3);
    double sum = 0.0;
    std::size_t count = 0;
    for (int y = 0; y < reference.height; ++y) {
        const cv::Vec3f* row = map32.ptr<cv::Vec3f>(y);
        for (int x = 0; x < reference.width; ++x) {
            if (!counted(mask, x, y)) continue;
            sum += double(row[x][0]) + double(row[x][1]) + double(row[x][2]);
            ++count;
        }
    }
    if (count == 0) return std::numeric_limits<double>::quiet_NaN();
    return sum / (3.0 * double(count));
}

ImageError image_error(ImageView<const glm::vec3> reference, ImageView<const glm::vec3> test,
                       ImageView<const uint8_t> mask) {
    return {.psnr = psnr(reference, test, mask),
            .ssim = ssim(reference, test, mask),
            .flip = flip(reference, test, mask)};
}

}  // namespace reprise
