#pragma once
// Where a command writes: never over what it reads, whole files only, and resumable.
#include <string>
#include <vector>

#include "reprise/core/exr.hpp"
#include "reprise/core/status.hpp"

namespace reprise::cli {

// What a command reads (folders or files) and what the user allowed.
struct OutputRules {
    std::vector<std::string> inputs;
    // --overwrite-inputs: writing where inputs are is allowed; frames are then staged in a
    // hidden folder and moved into place only after every input has been read.
    bool overwrite_inputs = false;
};

// Refuses an output that is an input, a folder that holds input frames, anything in or below an
// input folder that a sequence reader would read (every folder, .exr, cameras.json), symbolic
// links resolved: "--out X is the input X: ...". `folder`: the output is a folder of frames.
Status check_output(const std::string& option, const std::string& output, bool folder,
                    const OutputRules& rules);

// A folder of output frames. Frames are written whole (write_frame renames a finished temporary
// file), so a killed run leaves only complete frame_NNNNN.exr files.
class OutputFolder {
public:
    // Checks `dir` against the rules and creates it. `job` describes the run (its arguments);
    // it is kept in DIR/.reprise-run so that `resume` continues only the same run (empty: not
    // recorded, as for a farm's chunks that share one folder).
    Status open(const std::string& dir, const OutputRules& rules, const std::string& job,
                bool resume);
    // frame_00000.exr .. frame_{n-1}: complete frames a resumed run keeps.
    int frames_on_disk() const { return on_disk_; }
    std::string frame(int index) const { return frame_path(write_dir_, index); }
    Status write(int index, const Frame& frame, const WriteOptions& options = {}) const;
    // Moves staged frames into place (with --overwrite-inputs); nothing to do otherwise.
    Status finish();

private:
    std::string dir_, write_dir_;
    int on_disk_ = 0;
};

// Files written whole: the content goes to partial_path(path) (".NAME.partial" beside it), then
// commit_partial renames it over `path`, or removes it when the write failed.
std::string partial_path(const std::string& path);
Status commit_partial(const std::string& path, bool written);

// The whole of a small text file (a run record); empty when there is none.
std::string read_text(const std::string& path);

// Reads every frame's header and refuses a sequence whose frames differ in size, naming the
// first that does: commands that make one output sequence need one size.
Status check_one_size(const Sequence& sequence, const std::string& command);

}  // namespace reprise::cli
