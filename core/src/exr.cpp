// Sequences: folders of EXR frames.
#include "reprise/core/exr.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>

namespace reprise {
namespace {

namespace fs = std::filesystem;

bool is_exr(const fs::path& file) {
    std::string ext = file.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext == ".exr" && file.filename().string().front() != '.';
}

}  // namespace

bool natural_less(const std::string& a, const std::string& b) {
    auto digit = [](char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; };
    std::size_t i = 0, j = 0;
    while (i < a.size() && j < b.size()) {
        if (digit(a[i]) && digit(b[j])) {
            while (i < a.size() && a[i] == '0') ++i;
            while (j < b.size() && b[j] == '0') ++j;
            std::size_t i_end = i, j_end = j;
            while (i_end < a.size() && digit(a[i_end])) ++i_end;
            while (j_end < b.size() && digit(b[j_end])) ++j_end;
            if (i_end - i != j_end - j) return i_end - i < j_end - j;
            if (int c = a.compare(i, i_end - i, b, j, j_end - j); c != 0) return c < 0;
            i = i_end;
            j = j_end;
        } else {
            if (a[i] != b[j])
                return static_cast<unsigned char>(a[i]) < static_cast<unsigned char>(b[j]);
            ++i;
            ++j;
        }
    }
    if (a.size() - i != b.size() - j) return a.size() - i < b.size() - j;
    return a < b;  // equal up to leading zeros: keep a total order
}

Status open_sequence(const std::string& path, Sequence& sequence) {
    sequence = Sequence{};
    std::error_code ec;
    const fs::file_status status = fs::status(path, ec);
    if (!fs::exists(status)) return Status::error(path + ": no such file or folder");
    if (fs::is_directory(status)) {
        for (fs::directory_iterator it(path, ec), end; !ec && it != end; it.increment(ec))
            if (is_exr(it->path()) && it->is_regular_file(ec))
                sequence.files.push_back(it->path().string());
        if (ec) return Status::error(path + ": cannot list the folder: " + ec.message());
        if (sequence.files.empty()) return Status::error(path + ": no .exr files in the folder");
        std::sort(sequence.files.begin(), sequence.files.end(), natural_less);
    } else {
        sequence.files.push_back(path);
    }
    FrameHeader header;
    REPRISE_TRY(read_frame_header(sequence.files.front(), header));
    sequence.fps = header.fps;
    const fs::path cameras = fs::path(sequence.files.front()).parent_path() / "cameras.json";
    if (fs::exists(cameras, ec))
        REPRISE_TRY(read_cameras_json(cameras.string(), sequence.files, sequence.cameras));
    return {};
}

std::string frame_path(const std::string& dir, int index) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.exr", index);
    return (fs::path(dir) / name).string();
}

}  // namespace reprise
