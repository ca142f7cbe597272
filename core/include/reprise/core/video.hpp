#pragma once
// H.264 MP4 video through the `ffmpeg` executable: frames are piped to it as raw RGB.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "reprise/core/visualize.hpp"

namespace reprise {

struct VideoOptions {
    double fps = 30.0;
    std::string ffmpeg = "ffmpeg";  // executable, looked up on PATH
    int crf = 18;                   // x264 quality, 0 (lossless) .. 51
};

// Push frames one at a time; close() waits for ffmpeg and reports its failure.
// Odd sizes are padded to even (yuv420p) by repeating the last column / row.
class VideoWriter {
public:
    VideoWriter() = default;
    VideoWriter(const VideoWriter&) = delete;
    VideoWriter& operator=(const VideoWriter&) = delete;
    ~VideoWriter();

    Status open(const std::string& path, int width, int height, const VideoOptions& options = {});
    Status write(ImageView<const Rgb8> frame);
    Status close();
    bool is_open() const { return pid_ > 0; }
    int frames_written() const { return frames_; }

private:
    std::string path_;
    int pid_ = -1;
    int fd_ = -1;
    int width_ = 0, height_ = 0;
    int frames_ = 0;
    std::vector<uint8_t> buffer_;  // one padded frame
};

Status write_mp4(const std::string& path, std::span<const ImageView<const Rgb8>> frames,
                 const VideoOptions& options = {});

}  // namespace reprise
