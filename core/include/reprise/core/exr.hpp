#pragma once
// Frames as multichannel OpenEXR files and sequences as folders of them (OpenImageIO).
#include <string>
#include <vector>

#include "reprise/core/frame.hpp"

namespace reprise {

// Writes R,G,B,A,Z,motion.x,motion.y,N.X,N.Y,N.Z,id (absent buffers are left out) and the camera:
// worldToCamera, worldToNDC and the reprise:* attributes of docs/conventions.md.
Status write_frame(const std::string& path, const Frame& frame);

// Reads a reprise frame or a Blender multilayer EXR render (Combined, Depth, Vector passes).
// Every buffer is checked: a missing colour, a bad size or a truncated file is an error naming
// the file; NaN/Inf are kept as they are (depth +inf is background).
Status read_frame(const std::string& path, Frame& frame);

struct Sequence {
    std::vector<std::string> files;  // sorted by name
    double fps = 0.0;                // from the first frame's header; 0 when not recorded
};

// Lists a folder of EXR frames (reprise's frame_00000.exr… or a Blender render folder);
// a single .exr file is a sequence of one.
Status open_sequence(const std::string& path, Sequence& sequence);

// "DIR/frame_00042.exr"
std::string frame_path(const std::string& dir, int index);

}  // namespace reprise
