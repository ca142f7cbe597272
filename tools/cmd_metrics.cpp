// reprise metrics: PSNR, SSIM and FLIP of a sequence against a reference sequence.
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <opencv2/imgcodecs.hpp>

#include "args.hpp"
#include "commands.hpp"
#include "outputs.hpp"
#include "reprise/core/exr.hpp"
#include "reprise/core/metrics.hpp"

namespace reprise::cli {

namespace {

namespace fs = std::filesystem;

struct Options {
    std::string ref, test, csv, mask;
    double ppd = 67.0;
};

// One PNG for every frame, or a folder with one PNG per frame.
Status list_masks(const std::string& path, std::size_t frames, std::vector<std::string>& masks) {
    std::error_code ec;
    if (!fs::is_directory(path, ec)) {
        if (!fs::exists(path, ec))
            return Status::error("--mask " + path + ": no such file or folder");
        masks.assign(frames, path);
        return {};
    }
    for (fs::directory_iterator it(path, ec), end; !ec && it != end; it.increment(ec)) {
        std::string ext = it->path().extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(),
                       [](unsigned char c) { return char(std::tolower(c)); });
        if (ext == ".png" && it->is_regular_file(ec)) masks.push_back(it->path().string());
    }
    if (ec) return Status::error("--mask " + path + ": cannot list the folder: " + ec.message());
    std::sort(masks.begin(), masks.end(), natural_less);
    if (masks.size() != frames)
        return Status::error("--mask " + path + ": " + std::to_string(masks.size()) +
                             " PNG masks for " + std::to_string(frames) + " frames");
    return {};
}

Status read_mask(const std::string& path, int width, int height, Image<uint8_t>& mask) {
    cv::Mat m;
    try {
        m = cv::imread(path, cv::IMREAD_GRAYSCALE);
    } catch (const cv::Exception& e) {
        return Status::error(path + ": cannot read the mask (" + e.err + ")");
    }
    if (m.empty()) return Status::error(path + ": cannot read the mask as an image");
    if (m.cols != width || m.rows != height)
        return Status::error(path + ": mask is " + std::to_string(m.cols) + "x" +
                             std::to_string(m.rows) + ", the frames are " + std::to_string(width) +
                             "x" + std::to_string(height));
    mask.resize(width, height);
    for (int y = 0; y < height; ++y) std::copy_n(m.ptr<uint8_t>(y), width, &mask(0, y));
    return {};
}

std::string size_text(const Frame& f) {
    return std::to_string(f.width()) + "x" + std::to_string(f.height());
}

Status measure(const Options& o) {
    Sequence ref_seq, test_seq;
    REPRISE_TRY(open_sequence(o.ref, ref_seq));
    REPRISE_TRY(open_sequence(o.test, test_seq));
    const std::size_t n = ref_seq.files.size();
    if (test_seq.files.size() != n)
        return Status::error("--ref " + o.ref + " has " + std::to_string(n) +
                             " frames but --test " + o.test + " has " +
                             std::to_string(test_seq.files.size()));
    std::vector<std::string> masks;
    if (!o.mask.empty()) REPRISE_TRY(list_masks(o.mask, n, masks));

    std::unique_ptr<FILE, int (*)(FILE*)> csv(nullptr, &std::fclose);
    if (!o.csv.empty()) {
        REPRISE_TRY(check_output("--csv", o.csv, false,
                                 {.inputs = {o.ref, o.test}, .overwrite_inputs = false}));
        csv.reset(std::fopen(partial_path(o.csv).c_str(), "w"));
        if (!csv) return Status::error(o.csv + ": cannot open for writing");
        std::fputs("frame,psnr,ssim,flip\n", csv.get());
    }

    const bool tty = ::isatty(::fileno(stderr));
    std::printf("%6s %10s %8s %8s\n", "frame", "psnr", "ssim", "flip");
    Frame ref, test;
    Image<glm::vec3> ref_display, test_display;
    Image<uint8_t> mask;
    double sums[3] = {0, 0, 0};
    std::size_t counts[3] = {0, 0, 0};
    for (std::size_t i = 0; i < n; ++i) {
        const std::string& ref_file = ref_seq.files[i];
        const std::string& test_file = test_seq.files[i];
        REPRISE_TRY(read_frame(ref_file, ref));
        REPRISE_TRY(read_frame(test_file, test));
        if (ref.width() != test.width() || ref.height() != test.height())
            return Status::error("frame " + std::to_string(i) + ": " + ref_file + " is " +
                                 size_text(ref) + " but " + test_file + " is " + size_text(test));
        if (!masks.empty()) REPRISE_TRY(read_mask(masks[i], ref.width(), ref.height(), mask));

        ref_display.resize(ref.width(), ref.height());
        test_display.resize(ref.width(), ref.height());
        to_display(ref.color.view(), ref_display.view());
        to_display(test.color.view(), test_display.view());
        REPRISE_TRY(check_flip(ref.width(), ref.height(), o.ppd));
        ImageView<const uint8_t> m = masks.empty() ? ImageView<const uint8_t>{} : mask.view();
        const double values[3] = {
            psnr(ref_display.view(), test_display.view(), m),
            ssim(ref_display.view(), test_display.view(), m),
            flip(ref_display.view(), test_display.view(), m, {}, float(o.ppd))};
        for (int k = 0; k < 3; ++k)
            if (!std::isnan(values[k])) {
                sums[k] += values[k];
                ++counts[k];
            }

        if (tty) std::fputs("\r\033[K", stderr);
        std::printf("%6zu %10.4f %8.5f %8.5f\n", i, values[0], values[1], values[2]);
        std::fflush(stdout);
        if (csv)
            std::fprintf(csv.get(), "%zu,%.6f,%.6f,%.6f\n", i, values[0], values[1], values[2]);
        if (tty) std::fprintf(stderr, "\r[metrics] %zu/%zu", i + 1, n);
    }
    if (tty) std::fputs("\r\033[K", stderr);
    auto mean = [&](int k) { return counts[k] ? sums[k] / double(counts[k]) : NAN; };
    std::printf("%6s %10.4f %8.5f %8.5f\n", "mean", mean(0), mean(1), mean(2));
    std::fflush(stdout);
    std::fprintf(
        stderr, "[metrics] %zu frames%s\n", n,
        counts[0] < n ? " (frames whose mask selects no pixel left out of the means)" : "");
    if (csv) return commit_partial(o.csv, std::fclose(csv.release()) == 0);
    return {};
}

// A failed run leaves no partial CSV behind.
Status run(const Options& o) {
    Status status = measure(o);
    std::error_code ignored;
    if (!status.ok() && !o.csv.empty()) fs::remove(partial_path(o.csv), ignored);
    return status;
}

}  // namespace

int command_metrics(int argc, char** argv) {
    Options o;
    Args args(
        "metrics",
        "Per-frame PSNR (dB), SSIM and LDR-FLIP of --test against --ref, on display values\n"
        "(sRGB of linear colour clamped to [0, 1]), then their means. Both sequences need the\n"
        "same number of frames and sizes. Identical frames have PSNR inf.");
    args.option("--ref", &o.ref, "reference sequence (folder of EXR frames or one .exr)");
    args.option("--test", &o.test, "sequence to measure, frame by frame against --ref");
    args.option("--csv", &o.csv, "also write frame,psnr,ssim,flip rows to this file");
    args.option("--mask", &o.mask,
                "8-bit PNG masks (nonzero = counted): a folder, one per frame, or one PNG");
    args.option("--ppd", &o.ppd, "FLIP viewing condition, pixels per degree (default 67)");
    Status parsed = args.parse(argc, argv);
    if (parsed.ok() && !args.help_requested()) {
        if (o.ref.empty() || o.test.empty())
            parsed = Status::error("metrics: --ref and --test are both required");
        else if (Status ppd = check_flip_ppd(o.ppd); !ppd.ok())
            parsed = Status::error("metrics: --ppd: " + ppd.message());
    }
    if (!parsed.ok() || args.help_requested()) return report(args, parsed, {});
    return report(args, parsed, run(o));
}

}  // namespace reprise::cli
