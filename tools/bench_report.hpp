#pragma once
// What every `reprise bench` shares: timing (best of N, median, per-frame fastest), the standard
// CSV rows (scene,method,setting,frame,psnr,ssim,flip,ms and wider variants), 8-bit pictures and
// crops for worst-frame sheets, and the HTML report (report_html.hpp: Pareto front, plots).
#include <chrono>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "report_html.hpp"
#include "reprise/core/metrics.hpp"
#include "reprise/core/status.hpp"
#include "reprise/core/visualize.hpp"
#include "timing.hpp"

namespace reprise::cli {

// "31.42 dB".
std::string db(double psnr);

// Display values in [0, 1] <-> 8 bits (rounded, clamped).
void to_rgb8(ImageView<const glm::vec3> display, Image<Rgb8>& out);
void from_rgb8(ImageView<const Rgb8> shown, Image<glm::vec3>& out);

// The cw x ch window (even offsets) where `a` and `b` differ most (sum of absolute differences).
void worst_window(const Image<Rgb8>& a, const Image<Rgb8>& b, int cw, int ch, int& best_x,
                  int& best_y);
Image<Rgb8> crop(const Image<Rgb8>& image, int x0, int y0, int cw, int ch);
// The image with the window's border drawn in yellow.
Image<Rgb8> outlined(Image<Rgb8> image, int x0, int y0, int cw, int ch);

// A PNG sheet of full frames (images[0] is ours) in one row and, when the frames are larger than
// 200x112, below them the 200x112 window where images[0] differs most from `truth`, enlarged.
// Tiles are max(2 * crop width, 320) wide, at most max_tile_width.
Status write_worst_window_sheet(const std::string& path, std::vector<Image<Rgb8>> images,
                                std::vector<std::string> labels, const Image<Rgb8>& truth,
                                int max_tile_width = 1 << 20);

// A CSV file written row by row; closed by the destructor.
class CsvFile {
public:
    CsvFile() = default;
    ~CsvFile();
    CsvFile(const CsvFile&) = delete;
    CsvFile& operator=(const CsvFile&) = delete;

    // Creates the file and writes the header line (e.g. kErrorTimeColumns).
    Status open(const std::string& path, const std::string& header);
    // One line of the standard error-against-time columns (psnr %.4f, ssim/flip %.6f, ms %.4f)
    // followed by `extra` cells (already formatted, joined with commas) when given.
    void error_row(const std::string& scene, const std::string& method, const std::string& setting,
                   int frame, const ImageError& error, double ms,
                   const std::vector<std::string>& extra = {});
    // Any line: cells joined with commas.
    void row(const std::vector<std::string>& cells);
    void flush();
    FILE* file() { return file_; }
    const std::string& path() const { return path_; }

private:
    FILE* file_ = nullptr;
    std::string path_;
};

inline constexpr const char* kErrorTimeColumns = "scene,method,setting,frame,psnr,ssim,flip,ms";

// printf into a std::string (for CSV cells and table lines).
std::string strf(const char* pattern, ...) __attribute__((format(printf, 1, 2)));

}  // namespace reprise::cli
