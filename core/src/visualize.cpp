#include "reprise/core/visualize.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "reprise/core/frame.hpp"

namespace reprise {

namespace {

cv::Mat wrap(ImageView<const Rgb8> view) {
    return cv::Mat(view.height, view.width, CV_8UC3, const_cast<Rgb8*>(view.data),
                   std::size_t(view.stride) * sizeof(Rgb8));
}

uint8_t to_byte(float unit) {
    return uint8_t(std::lround(std::clamp(std::isnan(unit) ? 0.0f : unit, 0.0f, 1.0f) * 255.0f));
}

template <class In>
void check_same_size(ImageView<In> in, ImageView<Rgb8> out) {
    REPRISE_ASSERT(in.width == out.width && in.height == out.height);
}

bool valid_depth(float d) { return std::isfinite(d) && d > 0.0f; }

}  // namespace

void visualize_color(ImageView<const glm::vec4> linear, ImageView<Rgb8> out) {
    check_same_size(linear, out);
    for (int y = 0; y < linear.height; ++y)
        for (int x = 0; x < linear.width; ++x) {
            glm::vec4 c = linear(x, y);
            out(x, y) = {to_byte(linear_to_srgb(c.r)), to_byte(linear_to_srgb(c.g)),
                         to_byte(linear_to_srgb(c.b))};
        }
}

DepthRange depth_range(ImageView<const float> depth) {
    DepthRange range{std::numeric_limits<float>::max(), 0.0f};
    for (int y = 0; y < depth.height; ++y)
        for (int x = 0; x < depth.width; ++x) {
            float d = depth(x, y);
            if (!valid_depth(d)) continue;
            range.near = std::min(range.near, d);
            range.far = std::max(range.far, d);
        }
    return range.far > 0.0f ? range : DepthRange{};
}

void visualize_depth(ImageView<const float> depth, ImageView<Rgb8> out, DepthRange range) {
    check_same_size(depth, out);
    if (range.near == 0.0f && range.far == 0.0f) range = depth_range(depth);
    REPRISE_ASSERT((range.near == 0.0f && range.far == 0.0f) ||
                   (range.near > 0.0f && range.far >= range.near));
    constexpr float kFarGrey = 48.0f / 255.0f;  // keeps the farthest geometry off background black
    const float log_near = std::log(std::max(range.near, 1e-30f));
    const float log_span = std::log(std::max(range.far, 1e-30f)) - log_near;
    for (int y = 0; y < depth.height; ++y)
        for (int x = 0; x < depth.width; ++x) {
            float d = depth(x, y);
            if (!valid_depth(d)) {
                out(x, y) = Rgb8(0);
                continue;
            }
            float t = log_span > 0.0f ? std::clamp((std::log(d) - log_near) / log_span, 0.0f, 1.0f)
                                      : 0.0f;
            out(x, y) = Rgb8(to_byte(1.0f - t * (1.0f - kFarGrey)));
        }
}

float motion_length(ImageView<const glm::vec2> motion, float quantile) {
    REPRISE_ASSERT(quantile >= 0.0f && quantile <= 1.0f);
    std::vector<float> lengths;
    for (int y = 0; y < motion.height; ++y)
        for (int x = 0; x < motion.width; ++x) {
            float len = std::hypot(motion(x, y).x, motion(x, y).y);
            if (std::isfinite(len) && len > 0.0f) lengths.push_back(len);
        }
    if (lengths.empty()) return 0.0f;
    auto nth = lengths.begin() + std::ptrdiff_t(std::lround(quantile * float(lengths.size() - 1)));
    std::nth_element(lengths.begin(), nth, lengths.end());
    return *nth;
}

void visualize_motion(ImageView<const glm::vec2> motion, ImageView<Rgb8> out, float saturate_at) {
    check_same_size(motion, out);
    if (!(saturate_at > 0.0f)) saturate_at = motion_length(motion);
    for (int y = 0; y < motion.height; ++y)
        for (int x = 0; x < motion.width; ++x) {
            glm::vec2 m = motion(x, y);
            float len = std::hypot(m.x, m.y);
            if (std::isnan(len)) {
                out(x, y) = Rgb8(0);
                continue;
            }
            float s = saturate_at > 0.0f ? std::min(len / saturate_at, 1.0f) : 0.0f;
            if (std::isinf(len)) s = 1.0f;
            float hue = std::atan2(m.y, m.x) *
                        (180.0f / std::numbers::pi_v<float>);  // degrees, (-180, 180]
            if (hue < 0.0f) hue += 360.0f;
            float h = hue / 60.0f;
            float c = s;
            float second = c * (1.0f - std::abs(std::fmod(h, 2.0f) - 1.0f));
            glm::vec3 rgb = h < 1   ? glm::vec3(c, second, 0)
                            : h < 2 ? glm::vec3(second, c, 0)
                            : h < 3 ? glm::vec3(0, c, second)
                            : h < 4 ? glm::vec3(0, second, c)
                            : h < 5 ? glm::vec3(second, 0, c)
                                    : glm::vec3(c, 0, second);
            rgb += 1.0f - c;  // value 1: zero motion is white
            out(x, y) = {to_byte(rgb.r), to_byte(rgb.g), to_byte(rgb.b)};
        }
}

void visualize_normal(ImageView<const glm::vec3> normal, ImageView<Rgb8> out) {
    check_same_size(normal, out);
    for (int y = 0; y < normal.height; ++y)
        for (int x = 0; x < normal.width; ++x) {
            glm::vec3 n = normal(x, y);
            float len2 = n.x * n.x + n.y * n.y + n.z * n.z;
            if (!(len2 > 0.0f) || !std::isfinite(len2)) {
                out(x, y) = Rgb8(0);
                continue;
            }
            glm::vec3 c = n * 0.5f + 0.5f;
            out(x, y) = {to_byte(c.r), to_byte(c.g), to_byte(c.b)};
        }
}

Rgb8 id_color(uint32_t id) {
    if (id == 0) return Rgb8(0);
    uint32_t h = id;
    h ^= h >> 16;
    h *= 0x7feb352du;
    h ^= h >> 15;
    h *= 0x846ca68bu;
    h ^= h >> 16;
    auto channel = [](uint32_t byte) { return uint8_t(64 + byte * 191 / 255); };  // never black
    return {channel(h & 0xff), channel((h >> 8) & 0xff), channel((h >> 16) & 0xff)};
}

void visualize_id(ImageView<const uint32_t> id, ImageView<Rgb8> out) {
    check_same_size(id, out);
    for (int y = 0; y < id.height; ++y)
        for (int x = 0; x < id.width; ++x) out(x, y) = id_color(id(x, y));
}

Image<Rgb8> contact_sheet(std::span<const Tile> tiles, const SheetOptions& options) {
    REPRISE_ASSERT(options.columns > 0 && options.tile_width >= 0 && options.gap >= 0 &&
                   options.label_height >= 0);
    auto scaled = [&](const Tile& t) {
        if (t.image.empty() || options.tile_width == 0)
            return cv::Size(t.image.width, t.image.height);
        int h = int(std::lround(double(t.image.height) * options.tile_width / t.image.width));
        return cv::Size(options.tile_width, std::max(1, h));
    };
    cv::Size cell(0, 0);
    for (const Tile& t : tiles) {
        if (t.image.empty()) continue;
        cv::Size s = scaled(t);
        cell = {std::max(cell.width, s.width), std::max(cell.height, s.height)};
    }
    if (cell.width == 0) cell = {options.tile_width > 0 ? options.tile_width : 64, 48};

    const int columns = std::min<int>(options.columns, std::max<std::size_t>(tiles.size(), 1));
    const int rows = int((tiles.size() + options.columns - 1) / options.columns);
    const int gap = options.gap, label = options.label_height;
    const Rgb8 background(32);
    Image<Rgb8> sheet(columns * cell.width + (columns + 1) * gap,
                      rows * (label + cell.height) + (rows + 1) * gap, background);
    if (tiles.empty()) return sheet;
    cv::Mat canvas(sheet.height(), sheet.width(), CV_8UC3, sheet.data());

    const double font_scale = label / 40.0;
    for (std::size_t i = 0; i < tiles.size(); ++i) {
        const Tile& t = tiles[i];
        int x0 = gap + int(i % options.columns) * (cell.width + gap);
        int y0 = gap + int(i / options.columns) * (label + cell.height + gap);
        if (label > 0 && !t.label.empty()) {
            cv::Mat strip = canvas(cv::Rect(x0, y0, cell.width, label));
            int baseline = 0;
            cv::Size text =
                cv::getTextSize(t.label, cv::FONT_HERSHEY_SIMPLEX, font_scale, 1, &baseline);
            int y = (label + text.height) / 2;
            cv::putText(strip, t.label, cv::Point(2, y), cv::FONT_HERSHEY_SIMPLEX, font_scale,
                        cv::Scalar(230, 230, 230), 1, cv::LINE_AA);
        }
        cv::Mat target = canvas(cv::Rect(x0, y0 + label, cell.width, cell.height));
        if (t.image.empty()) {
            target.setTo(cv::Scalar(0, 0, 0));
            continue;
        }
        cv::Size s = scaled(t);
        cv::Mat place = target(
            cv::Rect((cell.width - s.width) / 2, (cell.height - s.height) / 2, s.width, s.height));
        cv::Mat source = wrap(t.image);
        if (s == source.size()) {
            source.copyTo(place);
        } else {
            bool shrink = s.width < source.cols;
            cv::resize(source, place, s, 0, 0, shrink ? cv::INTER_AREA : cv::INTER_LINEAR);
        }
    }
    return sheet;
}

Status write_png(const std::string& path, ImageView<const Rgb8> image) {
    if (image.empty()) return Status::error(path + ": nothing to write (empty image)");
    cv::Mat bgr;
    cv::cvtColor(wrap(image), bgr, cv::COLOR_RGB2BGR);
    try {
        if (!cv::imwrite(path, bgr)) return Status::error(path + ": cannot write the image");
    } catch (const cv::Exception& e) {
        return Status::error(path + ": cannot write the image (" + e.err + ")");
    }
    return {};
}

}  // namespace reprise
