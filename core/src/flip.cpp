// LDR-FLIP, written from the equations of Andersson, Nilsson, Akenine-Möller, Oskarsson, Åström
// and Fairchild, "FLIP: A Difference Evaluator for Alternating Images", HPG 2020.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "reprise/core/frame.hpp"
#include "reprise/core/memory_limit.hpp"
#include "reprise/core/metrics.hpp"

namespace reprise {

namespace {

constexpr float kQc = 0.7f;   // colour error exponent
constexpr float kPc = 0.4f;   // knee of the colour error remapping, fraction of cmax
constexpr float kPt = 0.95f;  // error at the knee
constexpr float kW = 0.082f;  // feature width, degrees
constexpr float kQf = 0.5f;   // feature error exponent

// Linear sRGB (D65) <-> CIE XYZ.
glm::vec3 rgb_to_xyz(glm::vec3 c) {
    return {0.4124564f * c.r + 0.3575761f * c.g + 0.1804375f * c.b,
            0.2126729f * c.r + 0.7151522f * c.g + 0.0721750f * c.b,
            0.0193339f * c.r + 0.1191920f * c.g + 0.9503041f * c.b};
}
glm::vec3 xyz_to_rgb(glm::vec3 c) {
    return {3.2404542f * c.x - 1.5371385f * c.y - 0.4985314f * c.z,
            -0.9692660f * c.x + 1.8760108f * c.y + 0.0415560f * c.z,
            0.0556434f * c.x - 0.2040259f * c.y + 1.0572252f * c.z};
}

const glm::vec3 kWhite = rgb_to_xyz(glm::vec3(1.0f));

// YCxCz: the linearized CIELAB opponent space used for the CSF filtering.
glm::vec3 xyz_to_ycxcz(glm::vec3 c) {
    glm::vec3 n = c / kWhite;
    return {116.0f * n.y - 16.0f, 500.0f * (n.x - n.y), 200.0f * (n.y - n.z)};
}
glm::vec3 ycxcz_to_xyz(glm::vec3 c) {
    float y = (c.x + 16.0f) / 116.0f;
    return glm::vec3(c.y / 500.0f + y, y, y - c.z / 200.0f) * kWhite;
}

float lab_f(float t) {
    constexpr float d = 6.0f / 29.0f;
    return t > d * d * d ? std::cbrt(t) : t / (3.0f * d * d) + 4.0f / 29.0f;
}

// CIELAB with the Hunt adjustment: chroma scaled by 0.01 L.
glm::vec3 hunt_lab(glm::vec3 rgb) {
    glm::vec3 n = rgb_to_xyz(rgb) / kWhite;
    float fx = lab_f(n.x), fy = lab_f(n.y), fz = lab_f(n.z);
    float l = 116.0f * fy - 16.0f;
    return {l, 0.01f * l * 500.0f * (fx - fy), 0.01f * l * 200.0f * (fy - fz)};
}

float hyab(glm::vec3 a, glm::vec3 b) {
    return std::abs(a.x - b.x) + std::hypot(a.y - b.y, a.z - b.z);
}

// Spatial CSF of one opponent channel: a sum of (at most two) Gaussians, with frequency-domain
// amplitudes a and widths b (degrees^2).
struct Csf {
    float a1, b1, a2, b2;
};
constexpr Csf kCsfAchromatic{1.0f, 0.0047f, 0.0f, 1e-5f};
constexpr Csf kCsfRedGreen{1.0f, 0.0053f, 0.0f, 1e-5f};
constexpr Csf kCsfBlueYellow{34.1f, 0.04f, 13.5f, 0.025f};

// Filter radius (pixels) of a CSF whose widest Gaussian has width b (degrees^2).
int csf_radius(double b_max, double ppd) {
    constexpr double pi = std::numbers::pi;
    return std::max(1, int(std::ceil(3.0 * std::sqrt(b_max / (2.0 * pi * pi)) * ppd)));
}

int feature_radius(double ppd) { return std::max(1, int(std::ceil(3.0 * 0.5 * kW * ppd))); }

// Filters `plane` in place with the CSF, normalized to unit sum, sampled at 1/ppd degrees.
void filter_csf(cv::Mat& plane, const Csf& csf, float ppd) {
    constexpr double pi = std::numbers::pi;
    double b_max = std::max(csf.a2 != 0.0f ? csf.b2 : 0.0f, csf.b1);
    const int radius = csf_radius(b_max, ppd);

    struct Term {
        cv::Mat kernel;
        double weight;
    };
    std::vector<Term> terms;
    double total = 0.0;
    for (auto [a, b] : {std::pair{csf.a1, csf.b1}, std::pair{csf.a2, csf.b2}}) {
        if (a == 0.0f) continue;
        cv::Mat kernel(2 * radius + 1, 1, CV_32F);
        double sum = 0.0;
        for (int i = -radius; i <= radius; ++i) {
            double x = i / double(ppd);
            kernel.at<float>(i + radius) = float(std::exp(-pi * pi * x * x / b));
            sum += kernel.at<float>(i + radius);
        }
        double weight = a * std::sqrt(pi / b);
        total += weight * sum * sum;
        terms.push_back({kernel, weight});
    }
    cv::Mat source = plane.clone(), filtered;
    for (std::size_t t = 0; t < terms.size(); ++t) {
        cv::Mat kx = terms[t].kernel * (terms[t].weight / total);
        cv::sepFilter2D(source, t == 0 ? plane : filtered, CV_32F, kx, terms[t].kernel,
                        cv::Point(-1, -1), 0.0, cv::BORDER_REPLICATE);
        if (t > 0) plane += filtered;
    }
}

// 1D kernels of the feature detector: a unit-sum Gaussian and its first and second
// derivatives, each with positive weights summing to 1 and negative weights to -1.
struct FeatureKernels {
    cv::Mat gauss, first, second;
};

FeatureKernels feature_kernels(float ppd) {
    double sigma = 0.5 * kW * ppd;
    int radius = feature_radius(ppd);
    int n = 2 * radius + 1;
    FeatureKernels k{cv::Mat(n, 1, CV_32F), cv::Mat(n, 1, CV_32F), cv::Mat(n, 1, CV_32F)};
    std::vector<double> g(n), d1(n), d2(n);
    double g_sum = 0.0;
    for (int i = -radius; i <= radius; ++i) {
        g[i + radius] = std::exp(-double(i) * i / (2.0 * sigma * sigma));
        g_sum += g[i + radius];
    }
    for (int i = -radius; i <= radius; ++i) {
        g[i + radius] /= g_sum;
        d1[i + radius] = -i * g[i + radius];
        d2[i + radius] = (double(i) * i / (sigma * sigma) - 1.0) * g[i + radius];
    }
    auto balance = [](std::vector<double>& d) {
        double pos = 0.0, neg = 0.0;
        for (double v : d) (v > 0 ? pos : neg) += std::abs(v);
        for (double& v : d) v = v > 0 ? (pos > 0 ? v / pos : 0) : (neg > 0 ? v / neg : 0);
    };
    balance(d1);
    balance(d2);
    for (int i = 0; i < n; ++i) {
        k.gauss.at<float>(i) = float(g[i]);
        k.first.at<float>(i) = float(d1[i]);
        k.second.at<float>(i) = float(d2[i]);
    }
    return k;
}

// What FLIP keeps of one image: Hunt-adjusted L*a*b* of the CSF-filtered image, and the
// edge and point strengths of its achromatic channel.
struct Prepared {
    std::vector<glm::vec3> lab;
    cv::Mat edges, points;
};

Prepared prepare(ImageView<const glm::vec3> display, float ppd, const FeatureKernels& fk) {
    int w = display.width, h = display.height;
    cv::Mat y(h, w, CV_32F), cx(h, w, CV_32F), cz(h, w, CV_32F), lum(h, w, CV_32F);
    for (int j = 0; j < h; ++j) {
        for (int i = 0; i < w; ++i) {
            glm::vec3 d = display(i, j);
            glm::vec3 linear(srgb_to_linear(d.r), srgb_to_linear(d.g), srgb_to_linear(d.b));
            glm::vec3 o = xyz_to_ycxcz(rgb_to_xyz(linear));
            y.at<float>(j, i) = o.x;
            cx.at<float>(j, i) = o.y;
            cz.at<float>(j, i) = o.z;
            lum.at<float>(j, i) = (o.x + 16.0f) / 116.0f;
        }
    }
    filter_csf(y, kCsfAchromatic, ppd);
    filter_csf(cx, kCsfRedGreen, ppd);
    filter_csf(cz, kCsfBlueYellow, ppd);

    Prepared p;
    p.lab.resize(std::size_t(w) * h);
    for (int j = 0; j < h; ++j) {
        for (int i = 0; i < w; ++i) {
            glm::vec3 o(y.at<float>(j, i), cx.at<float>(j, i), cz.at<float>(j, i));
            glm::vec3 rgb = glm::clamp(xyz_to_rgb(ycxcz_to_xyz(o)), 0.0f, 1.0f);
            p.lab[std::size_t(j) * w + i] = hunt_lab(rgb);
        }
    }

    auto strength = [&](const cv::Mat& kernel) {
        cv::Mat gx, gy, out;
        cv::sepFilter2D(lum, gx, CV_32F, kernel, fk.gauss, cv::Point(-1, -1), 0.0,
                        cv::BORDER_REPLICATE);
        cv::sepFilter2D(lum, gy, CV_32F, fk.gauss, kernel, cv::Point(-1, -1), 0.0,
                        cv::BORDER_REPLICATE);
        cv::magnitude(gx, gy, out);
        return out;
    };
    p.edges = strength(fk.first);
    p.points = strength(fk.second);
    return p;
}

}  // namespace

static std::string number(double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", value);
    return text;
}

Status check_flip_ppd(double pixels_per_degree) {
    if (!(pixels_per_degree > 0.0) || pixels_per_degree > kMaxFlipPpd)
        return Status::error("FLIP: pixels per degree " + number(pixels_per_degree) +
                             " must be in (0, " + number(kMaxFlipPpd) + "]");
    return {};
}

std::uint64_t flip_memory(int width, int height, double pixels_per_degree) {
    REPRISE_ASSERT(width >= 0 && height >= 0 && check_flip_ppd(pixels_per_degree).ok());
    // Measured peaks (RSS): 45 bytes a pixel at 67 ppd (1920x1080), plus what OpenCV's separable
    // filters hold for a radius r: about (side + 2r) x (side + 16) floats for a few planes
    // (934 MB for 16x16 at 1e7 ppd, r = 1.35e6). Both rounded up.
    const std::uint64_t radius = std::max(csf_radius(kCsfBlueYellow.b1, pixels_per_degree),
                                          feature_radius(pixels_per_degree));
    const std::uint64_t side = std::uint64_t(std::max(width, height));
    const std::uint64_t pixels = std::uint64_t(width) * std::uint64_t(height);
    return pixels * 48 + (side + 2 * radius) * (side + 16) * 12;
}

Status check_flip(int width, int height, double pixels_per_degree) {
    REPRISE_TRY(check_flip_ppd(pixels_per_degree));
    return check_memory(flip_memory(width, height, pixels_per_degree),
                        "FLIP " + std::to_string(width) + "x" + std::to_string(height) + " at " +
                            number(pixels_per_degree) + " pixels per degree");
}

double flip(ImageView<const glm::vec3> reference, ImageView<const glm::vec3> test,
            ImageView<const uint8_t> mask, ImageView<float> error_map, float pixels_per_degree) {
    REPRISE_ASSERT(reference.width == test.width && reference.height == test.height);
    REPRISE_ASSERT(mask.empty() ||
                   (mask.width == reference.width && mask.height == reference.height));
    REPRISE_ASSERT(error_map.empty() ||
                   (error_map.width == reference.width && error_map.height == reference.height));
    REPRISE_ASSERT(check_flip_ppd(pixels_per_degree).ok());
    if (reference.empty()) return std::numeric_limits<double>::quiet_NaN();

    const float ppd = pixels_per_degree;
    FeatureKernels fk = feature_kernels(ppd);
    Prepared r = prepare(reference, ppd, fk);
    Prepared t = prepare(test, ppd, fk);

    // The largest colour difference: between Hunt-adjusted green and blue.
    const float cmax = std::pow(hyab(hunt_lab({0, 1, 0}), hunt_lab({0, 0, 1})), kQc);
    const float knee = kPc * cmax;

    double sum = 0.0;
    std::size_t count = 0;
    const int w = reference.width;
    for (int j = 0; j < reference.height; ++j) {
        for (int i = 0; i < w; ++i) {
            std::size_t k = std::size_t(j) * w + i;
            float color = std::pow(hyab(r.lab[k], t.lab[k]), kQc);
            color = color < knee ? kPt / knee * color
                                 : kPt + (color - knee) / (cmax - knee) * (1.0f - kPt);
            color = std::min(color, 1.0f);

            float edge = std::abs(r.edges.at<float>(j, i) - t.edges.at<float>(j, i));
            float point = std::abs(r.points.at<float>(j, i) - t.points.at<float>(j, i));
            float feature = std::pow(std::max(edge, point) / std::numbers::sqrt2_v<float>, kQf);
            feature = std::min(feature, 1.0f);

            float e = color > 0.0f ? std::pow(color, 1.0f - feature) : 0.0f;
            if (!error_map.empty()) error_map(i, j) = e;
            if (mask.empty() || mask(i, j) != 0) {
                sum += e;
                ++count;
            }
        }
    }
    return count > 0 ? sum / double(count) : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace reprise
