#include "outputs.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace reprise::cli {

namespace fs = std::filesystem;

namespace {

constexpr const char* kRunFile = ".reprise-run";
constexpr const char* kStaging = ".reprise-staging";

// The path with symbolic links resolved, also for a path that does not exist yet.
fs::path resolved(const std::string& path) {
    std::error_code ec;
    fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
    return ec ? fs::absolute(path).lexically_normal() : p;
}

bool inside_or_same(const fs::path& path, const fs::path& folder) {
    const auto [f, p] = std::mismatch(folder.begin(), folder.end(), path.begin(), path.end());
    return f == folder.end() || (f->empty() && std::next(f) == folder.end());  // "dir/"
}

// Files a sequence reader takes from a folder: frames and cameras.json.
bool read_as_input(const fs::path& file) {
    std::string ext = file.extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext == ".exr" || file.filename() == "cameras.json";
}

}  // namespace

Status check_output(const std::string& option, const std::string& output, bool folder,
                    const OutputRules& rules) {
    if (rules.overwrite_inputs) return {};
    const fs::path out = resolved(output);
    for (const std::string& input : rules.inputs) {
        std::error_code ec;
        const fs::path in = resolved(input);
        std::string why;
        if (out == in) {
            why = "is the input " + input;
        } else if (fs::is_directory(in, ec)) {
            // A folder of frames: nothing is written in it or below it, except files that no
            // sequence reader reads (a CSV of metrics, say).
            if (inside_or_same(out, in) && (folder || read_as_input(out)))
                why = "lies inside the input folder " + input;
        } else if (folder && out == in.parent_path() && read_as_input(in)) {
            why = "holds the input " + input;
        }
        if (!why.empty())
            return Status::error(option + " " + output + " " + why +
                                 ": writing there would overwrite what is still to be read "
                                 "(choose another output, or --overwrite-inputs if you mean it)");
    }
    return {};
}

Status OutputFolder::open(const std::string& dir, const OutputRules& rules, const std::string& job,
                          bool resume) {
    dir_ = write_dir_ = dir;
    on_disk_ = 0;
    if (resume && rules.overwrite_inputs)
        return Status::error("--resume and --overwrite-inputs cannot be combined");
    REPRISE_TRY(check_output("--out", dir, true, rules));
    std::error_code ec;
    const bool staged =
        rules.overwrite_inputs && !check_output("--out", dir, true, {rules.inputs}).ok();
    if (staged) {
        write_dir_ = (fs::path(dir) / kStaging).string();
        fs::remove_all(write_dir_, ec);
    }
    fs::create_directories(write_dir_, ec);
    if (ec) return Status::error(dir + ": cannot create the folder: " + ec.message());
    const fs::path run_file = fs::path(dir) / kRunFile;
    if (resume) {
        const bool recorded = fs::exists(run_file, ec);
        if (!recorded && fs::exists(frame_path(dir, 0), ec))
            return Status::error("--resume: " + dir +
                                 " holds frames but no record of the run that wrote them (" +
                                 kRunFile + ")");
        if (recorded && read_text(run_file.string()) != job)
            return Status::error("--resume: " + dir + " was written by another run (" +
                                 read_text(run_file.string()) +
                                 "); resume it with the same arguments");
        while (fs::exists(frame_path(dir, on_disk_), ec)) ++on_disk_;
        // A killed write leaves its hidden temporary file behind; nothing reads it.
        for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
            const std::string name = it->path().filename().string();
            if (name.size() > 4 && name[0] == '.' && name.ends_with(".tmp"))
                fs::remove(it->path(), ec);
        }
    }
    if (!job.empty()) std::ofstream(run_file, std::ios::trunc) << job;
    return {};
}

Status OutputFolder::write(int index, const Frame& frame, const WriteOptions& options) const {
    if (index < on_disk_) return {};  // resumed: already on disk
    return write_frame(frame_path(write_dir_, index), frame, options);
}

Status OutputFolder::finish() {
    if (write_dir_ == dir_) return {};
    std::error_code ec;
    for (fs::directory_iterator it(write_dir_, ec), end; !ec && it != end; it.increment(ec)) {
        fs::rename(it->path(), fs::path(dir_) / it->path().filename(), ec);
        if (ec)
            return Status::error(it->path().string() + ": cannot move into " + dir_ + ": " +
                                 ec.message());
    }
    fs::remove_all(write_dir_, ec);
    write_dir_ = dir_;
    return {};
}

std::string read_text(const std::string& path) {
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

std::string partial_path(const std::string& path) {
    const fs::path target(path);
    std::string name(1, '.');
    name += target.filename().string();
    name += ".partial";
    return (target.parent_path() / name).string();
}

Status commit_partial(const std::string& path, bool written) {
    std::error_code ec;
    if (written) fs::rename(partial_path(path), path, ec);
    if (!written || ec) {
        std::error_code ignored;
        fs::remove(partial_path(path), ignored);
        return Status::error(path + ": cannot write" + (ec ? ": " + ec.message() : ""));
    }
    return {};
}

Status check_one_size(const Sequence& sequence, const std::string& command) {
    FrameHeader first, header;
    for (std::size_t i = 0; i < sequence.files.size(); ++i) {
        REPRISE_TRY(read_frame_header(sequence.files[i], i ? header : first));
        if (i && (header.width != first.width || header.height != first.height))
            return Status::error(sequence.files[i] + " is " + std::to_string(header.width) + "x" +
                                 std::to_string(header.height) + ", but " + sequence.files[0] +
                                 " is " + std::to_string(first.width) + "x" +
                                 std::to_string(first.height) + ": " + command +
                                 " needs frames of one size (split the folder by size)");
    }
    return {};
}

}  // namespace reprise::cli
