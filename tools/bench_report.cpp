#include "bench_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <glm/common.hpp>
#include <utility>

namespace reprise::cli {

std::string strf(const char* pattern, ...) {
    char buffer[1024];
    va_list args;
    va_start(args, pattern);
    std::vsnprintf(buffer, sizeof buffer, pattern, args);
    va_end(args);
    return buffer;
}

std::string db(double psnr) { return strf("%.2f dB", psnr); }

void to_rgb8(ImageView<const glm::vec3> display, Image<Rgb8>& out) {
    out.resize(display.width, display.height);
    for (int y = 0; y < display.height; ++y)
        for (int x = 0; x < display.width; ++x) {
            glm::vec3 c = glm::clamp(display(x, y), 0.0f, 1.0f) * 255.0f + 0.5f;
            out(x, y) = Rgb8(uint8_t(c.x), uint8_t(c.y), uint8_t(c.z));
        }
}

void from_rgb8(ImageView<const Rgb8> shown, Image<glm::vec3>& out) {
    out.resize(shown.width, shown.height);
    for (int y = 0; y < shown.height; ++y)
        for (int x = 0; x < shown.width; ++x) out(x, y) = glm::vec3(shown(x, y)) / 255.0f;
}

void worst_window(const Image<Rgb8>& a, const Image<Rgb8>& b, int cw, int ch, int& best_x,
                  int& best_y) {
    const int w = a.width(), h = a.height();
    std::vector<double> sat(std::size_t(w + 1) * (h + 1), 0.0);  // summed-area table
    auto at = [&](int x, int y) -> double& { return sat[std::size_t(y) * (w + 1) + x]; };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            glm::ivec3 d = glm::abs(glm::ivec3(a(x, y)) - glm::ivec3(b(x, y)));
            at(x + 1, y + 1) = d.x + d.y + d.z + at(x, y + 1) + at(x + 1, y) - at(x, y);
        }
    double best = -1.0;
    best_x = best_y = 0;
    for (int y = 0; y + ch <= h; y += 2)
        for (int x = 0; x + cw <= w; x += 2) {
            double sum = at(x + cw, y + ch) - at(x, y + ch) - at(x + cw, y) + at(x, y);
            if (sum > best) best = sum, best_x = x, best_y = y;
        }
}

Image<Rgb8> crop(const Image<Rgb8>& image, int x0, int y0, int cw, int ch) {
    Image<Rgb8> out(cw, ch);
    for (int y = 0; y < ch; ++y)
        for (int x = 0; x < cw; ++x) out(x, y) = image(x0 + x, y0 + y);
    return out;
}

Image<Rgb8> outlined(Image<Rgb8> image, int x0, int y0, int cw, int ch) {
    const Rgb8 yellow(255, 220, 0);
    for (int x = x0; x < x0 + cw; ++x) image(x, y0) = image(x, y0 + ch - 1) = yellow;
    for (int y = y0; y < y0 + ch; ++y) image(x0, y) = image(x0 + cw - 1, y) = yellow;
    return image;
}

Status write_worst_window_sheet(const std::string& path, std::vector<Image<Rgb8>> images,
                                std::vector<std::string> labels, const Image<Rgb8>& truth,
                                int max_tile_width) {
    REPRISE_ASSERT(!images.empty() && images.size() == labels.size());
    const int w = truth.width(), h = truth.height();
    const int cw = std::min(w, 200), ch = std::min(h, 112);
    int x0 = 0, y0 = 0;
    worst_window(images[0], truth, cw, ch, x0, y0);
    const std::size_t columns = images.size();
    if (cw < w || ch < h)
        for (std::size_t i = 0; i < columns; ++i) {
            images.push_back(crop(images[i], x0, y0, cw, ch));
            images[i] = outlined(std::move(images[i]), x0, y0, cw, ch);
            labels.push_back(i == 0 ? "crop where ours errs most" : "same crop");
        }
    std::vector<Tile> tiles;
    for (std::size_t i = 0; i < images.size(); ++i) tiles.push_back({images[i].view(), labels[i]});
    Image<Rgb8> sheet = contact_sheet(
        tiles,
        {.columns = int(columns), .tile_width = std::min(std::max(2 * cw, 320), max_tile_width)});
    return write_png(path, sheet.view());
}

CsvFile::~CsvFile() {
    if (file_) std::fclose(file_);
}

Status CsvFile::open(const std::string& path, const std::string& header) {
    if (file_) std::fclose(file_);
    path_ = path;
    file_ = std::fopen(path.c_str(), "w");
    if (!file_) return Status::error(path + ": cannot write");
    std::fprintf(file_, "%s\n", header.c_str());
    return {};
}

void CsvFile::error_row(const std::string& scene, const std::string& method,
                        const std::string& setting, int frame, const ImageError& error, double ms,
                        const std::vector<std::string>& extra) {
    REPRISE_ASSERT(file_);
    std::fprintf(file_, "%s,%s,%s,%d,%.4f,%.6f,%.6f,%.4f", scene.c_str(), method.c_str(),
                 setting.c_str(), frame, error.psnr, error.ssim, error.flip, ms);
    for (const std::string& cell : extra) std::fprintf(file_, ",%s", cell.c_str());
    std::fputc('\n', file_);
}

void CsvFile::row(const std::vector<std::string>& cells) {
    REPRISE_ASSERT(file_);
    for (std::size_t i = 0; i < cells.size(); ++i)
        std::fprintf(file_, "%s%s", i ? "," : "", cells[i].c_str());
    std::fputc('\n', file_);
}

void CsvFile::flush() {
    if (file_) std::fflush(file_);
}

}  // namespace reprise::cli
