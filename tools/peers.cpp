#include "peers.hpp"

#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <glm/common.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/photo.hpp>
#include <opencv2/video/tracking.hpp>

namespace reprise::cli {

namespace {

std::string shell_quote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

cv::Mat as_mat(ImageView<const Rgb8> image) {
    static_assert(sizeof(Rgb8) == 3);
    return cv::Mat(image.height, image.width, CV_8UC3, const_cast<Rgb8*>(image.data),
                   std::size_t(image.stride) * sizeof(Rgb8));
}

}  // namespace

bool ffmpeg_has_minterpolate(const std::string& ffmpeg) {
    std::string command = shell_quote(ffmpeg) + " -hide_banner -h filter=minterpolate 2>&1";
    FILE* pipe = popen(command.c_str(), "r");
    if (!pipe) return false;
    std::string text;
    char buffer[4096];
    std::size_t n;
    while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) text.append(buffer, n);
    int status = pclose(pipe);
    return WIFEXITED(status) && WEXITSTATUS(status) == 0 &&
           text.find("minterpolate AVOptions") != std::string::npos;
}

Status ffmpeg_minterpolate(const std::vector<Image<Rgb8>>& input, int factor,
                           const std::string& scratch_dir, std::vector<Image<Rgb8>>& output,
                           double& seconds, const std::string& ffmpeg) {
    REPRISE_ASSERT(!input.empty() && factor >= 1);
    const int w = input[0].width(), h = input[0].height();
    const std::size_t frame_bytes = std::size_t(w) * h * 3;
    const std::string raw = scratch_dir + "/minterpolate_input.rgb";
    {
        std::ofstream file(raw, std::ios::binary);
        // minterpolate holds back the last frames for its motion search: two copies of the
        // last frame push every wanted frame out.
        for (std::size_t i = 0; i < input.size() + 2; ++i) {
            const Image<Rgb8>& f = input[std::min(i, input.size() - 1)];
            file.write(reinterpret_cast<const char*>(f.data()), std::streamsize(frame_bytes));
        }
        if (!file) return Status::error(raw + ": cannot write the ffmpeg input");
    }
    const std::size_t wanted = (input.size() - 1) * std::size_t(factor) + 1;
    std::string command = shell_quote(ffmpeg) +
                          " -hide_banner -loglevel error -nostdin -f rawvideo -pix_fmt rgb24 -s " +
                          std::to_string(w) + "x" + std::to_string(h) + " -r 30 -i " +
                          shell_quote(raw) +
                          " -vf minterpolate=fps=" + std::to_string(30 * factor) +
                          ":mi_mode=mci -f rawvideo -pix_fmt rgb24 - 2>/dev/null";
    output.clear();
    auto start = std::chrono::steady_clock::now();
    FILE* pipe = popen(command.c_str(), "r");
    if (!pipe) return Status::error("ffmpeg: cannot start '" + ffmpeg + "'");
    Image<Rgb8> frame(w, h);
    while (fread(frame.data(), 1, frame_bytes, pipe) == frame_bytes) {
        if (output.size() < wanted) output.push_back(frame);
    }
    int status = pclose(pipe);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::error_code ec;
    std::filesystem::remove(raw, ec);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        return Status::error("ffmpeg minterpolate failed (" + command + ")");
    if (output.size() < wanted)
        return Status::error("ffmpeg minterpolate gave " + std::to_string(output.size()) +
                             " frames, expected " + std::to_string(wanted));
    return {};
}

struct DisInterpolator::State {
    cv::Ptr<cv::DISOpticalFlow> flow =
        cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_MEDIUM);
    cv::Mat a, b, grey_a, grey_b, flow_ab, flow_ba, grid, map, warped_a, warped_b;
};

DisInterpolator::DisInterpolator() : state_(std::make_unique<State>()) {}
DisInterpolator::~DisInterpolator() = default;

void DisInterpolator::set_pair(ImageView<const Rgb8> a, ImageView<const Rgb8> b) {
    State& st = *state_;
    st.a = as_mat(a);
    st.b = as_mat(b);
    cv::cvtColor(st.a, st.grey_a, cv::COLOR_RGB2GRAY);
    cv::cvtColor(st.b, st.grey_b, cv::COLOR_RGB2GRAY);
    st.flow->calc(st.grey_a, st.grey_b, st.flow_ab);  // a(p) ~ b(p + flow_ab(p))
    st.flow->calc(st.grey_b, st.grey_a, st.flow_ba);
    if (st.grid.rows != a.height || st.grid.cols != a.width) {
        st.grid.create(a.height, a.width, CV_32FC2);
        for (int y = 0; y < a.height; ++y)
            for (int x = 0; x < a.width; ++x)
                st.grid.at<cv::Vec2f>(y, x) = cv::Vec2f(float(x), float(y));
    }
}

void DisInterpolator::interpolate(float s, ImageView<Rgb8> out) {
    State& st = *state_;
    // a is fetched at q - s * flow_ab(q) and b at q - (1 - s) * flow_ba(q): the flow at the
    // target pixel stands in for the flow at the source point (the usual approximation).
    cv::scaleAdd(st.flow_ab, -s, st.grid, st.map);
    cv::remap(st.a, st.warped_a, st.map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    cv::scaleAdd(st.flow_ba, -(1.0f - s), st.grid, st.map);
    cv::remap(st.b, st.warped_b, st.map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    cv::Mat target = as_mat(out);
    cv::addWeighted(st.warped_a, 1.0 - s, st.warped_b, s, 0.0, target);
}

void inpaint_telea(ImageView<glm::vec3> display, ImageView<const uint8_t> holes) {
    const int w = display.width, h = display.height;
    cv::Mat rgb(h, w, CV_8UC3), mask(h, w, CV_8U), filled;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            glm::vec3 c = glm::clamp(display(x, y), 0.0f, 1.0f) * 255.0f + 0.5f;
            rgb.at<cv::Vec3b>(y, x) = cv::Vec3b(uint8_t(c.x), uint8_t(c.y), uint8_t(c.z));
            mask.at<uint8_t>(y, x) = holes(x, y) ? 255 : 0;
        }
    cv::inpaint(rgb, mask, filled, 3.0, cv::INPAINT_TELEA);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            if (holes(x, y)) {
                cv::Vec3b c = filled.at<cv::Vec3b>(y, x);
                display(x, y) = glm::vec3(c[0], c[1], c[2]) / 255.0f;
            }
}

void RenderedVectorsInterpolator::interpolate(const Frame& a, const Frame& b, float s,
                                              Image<glm::vec3>& display) {
    const int w = b.width(), h = b.height();
    const Frame* sides[2] = {&a, &b};
    const float factors[2] = {-s, 1.0f - s};
    for (int k = 0; k < 2; ++k) {
        color_[k].assign(w, h, glm::vec3(0.0f));
        depth_[k].assign(w, h, INFINITY);
        covered_[k].assign(w, h, 0);
        const Frame& f = *sides[k];
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const float z = f.depth(x, y);
                const glm::vec2 to = glm::vec2(x + 0.5f, y + 0.5f) + factors[k] * f.motion(x, y);
                if (!(z == z) ||
                    !(to.x >= 0.0f && to.y >= 0.0f && to.x < float(w) && to.y < float(h)))
                    continue;
                const int tx = int(to.x), ty = int(to.y);
                if (!covered_[k](tx, ty) || z < depth_[k](tx, ty)) {
                    covered_[k](tx, ty) = 1;
                    depth_[k](tx, ty) = z;
                    color_[k](tx, ty) = glm::vec3(f.color(x, y));
                }
            }
    }
    display.resize(w, h);
    holes_.resize(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float za = depth_[0](x, y), zb = depth_[1](x, y);
            const bool in_a = covered_[0](x, y), in_b = covered_[1](x, y);
            glm::vec3 c(0.0f);
            if (in_a && in_b && (za == zb || std::abs(za - zb) <= 0.02f * std::min(za, zb))) {
                c = (1.0f - s) * color_[0](x, y) + s * color_[1](x, y);
            } else if (in_a && in_b) {
                c = za < zb ? color_[0](x, y) : color_[1](x, y);
            } else if (in_a || in_b) {
                c = in_a ? color_[0](x, y) : color_[1](x, y);
            }
            holes_(x, y) = !(in_a || in_b);
            display(x, y) =
                glm::vec3(linear_to_srgb(c.r), linear_to_srgb(c.g), linear_to_srgb(c.b));
        }
    inpaint_telea(display.view(), holes_.view());
}

}  // namespace reprise::cli
