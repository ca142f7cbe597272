#pragma once
// Frames as multichannel OpenEXR files and sequences as folders of them (OpenImageIO).
#include <string>
#include <string_view>
#include <vector>

#include "reprise/core/frame.hpp"

namespace reprise {

enum class ExrLayout {
    Reprise,  // R,G,B,A,Z,motion.x,motion.y,N.X,N.Y,N.Z,id
    // Blender's multilayer render names, which Blender (and Nuke, oiiotool) open as layers:
    // ViewLayer.Combined.R/G/B/A, ViewLayer.Depth.Z (background 1e10), ViewLayer.Vector.X/Y/Z/W
    // (+y up; Z,W = X,Y), ViewLayer.Normal.X/Y/Z, ViewLayer.IndexOB.X (float).
    Blender,
};

struct WriteOptions {
    ExrLayout layout = ExrLayout::Reprise;
};

// Writes the frame's buffers (absent buffers are left out) with the channel names of
// `options.layout`, and the camera: worldToCamera, worldToNDC and the reprise:* attributes of
// docs/exr_format.md. Writes a temporary file beside `path` and renames it, so a failed write
// never leaves a broken frame. read_frame reads both layouts back to the same Frame.
Status write_frame(const std::string& path, const Frame& frame, const WriteOptions& options = {});

// Reads a reprise frame or a Blender multilayer EXR render (Combined, Depth, Vector, Normal,
// IndexOB passes, converted to reprise's conventions). Every buffer is checked: a missing colour,
// a bad size or a truncated file is an error naming the file; NaN/Inf are kept as they are
// (depth +inf is background). On error the frame's contents are unspecified.
Status read_frame(const std::string& path, Frame& frame);

// What a frame file's header says, read without its pixels.
struct FrameHeader {
    int width = 0;
    int height = 0;
    std::vector<std::string> channels;       // as stored: "R", "ViewLayer.Combined.R", ...
    std::vector<std::string> channel_types;  // "half", "float" or "uint", one per channel
    bool blender = false;                    // a Blender multilayer render
    bool has_camera = false;                 // worldToCamera or reprise:projection present
    Camera camera;
    double fps = 0.0;
};
Status read_frame_header(const std::string& path, FrameHeader& header);

struct Sequence {
    std::vector<std::string> files;  // sorted by name (frame_9 before frame_10)
    double fps = 0.0;                // from the first frame's header; 0 when not recorded
    // From a cameras.json beside the frames, one per file (a default Camera where it names
    // none); empty without one.
    std::vector<Camera> cameras;
};

// Lists a folder of EXR frames (reprise's frame_00000.exr… or a Blender render folder), sorted
// with digit runs compared as numbers; a single file is a sequence of one. A cameras.json beside
// the frames (docs/exr_format.md) gives the cameras that the files do not carry.
Status open_sequence(const std::string& path, Sequence& sequence);

// Frame `index` of the sequence; one without a camera gets the sequence's (cameras.json).
Status read_frame(const Sequence& sequence, std::size_t index, Frame& frame);

// cameras.json: {"frames": [{"file": "0001.exr", "view": [16], "projection": [16],
// "prev_view": [16], "prev_projection": [16], "near": n, "far": f, "time": s}, ...]}, matrices
// column-major as in OpenGL; the cameras of `files` matched by file name.
Status read_cameras_json(const std::string& path, const std::vector<std::string>& files,
                         std::vector<Camera>& cameras);
// The same on the file's text; `path` only names it in errors.
Status parse_cameras_json(std::string_view text, const std::string& path,
                          const std::vector<std::string>& files, std::vector<Camera>& cameras);

// OpenEXR's standard camera attributes, column-vector form (the file holds their transposes):
// worldToCamera maps to RenderMan's camera space (+x right, +y up, +z forward: the view with z
// negated); worldToNDC maps to (0,0) at the image's top-left and (1,1) at its bottom-right corner
// after the division by w.
glm::mat4 exr_world_to_camera(const glm::mat4& view);
glm::mat4 exr_world_to_ndc(const glm::mat4& projection, const glm::mat4& view);

// "frame_9" < "frame_10": runs of digits compare as numbers, the rest byte by byte; the order
// of open_sequence.
bool natural_less(const std::string& a, const std::string& b);

// "DIR/frame_00042.exr"
std::string frame_path(const std::string& dir, int index);

}  // namespace reprise
