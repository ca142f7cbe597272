#include "reprise/core/video.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>

extern char** environ;

namespace reprise {

namespace {

std::string number(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", v);
    return text;
}

std::string exit_text(int wait_status) {
    if (WIFEXITED(wait_status)) return "exit status " + std::to_string(WEXITSTATUS(wait_status));
    if (WIFSIGNALED(wait_status))
        return "killed by signal " + std::to_string(WTERMSIG(wait_status));
    return "wait status " + std::to_string(wait_status);
}

// Writes everything or fails with errno; a reader that went away gives EPIPE, not SIGPIPE.
bool write_all(int fd, const uint8_t* data, std::size_t size) {
    sigset_t pipe_signal, old;
    sigemptyset(&pipe_signal);
    sigaddset(&pipe_signal, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &pipe_signal, &old);
    bool ok = true;
    while (size > 0) {
        ssize_t n = ::write(fd, data, size);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            ok = false;
            break;
        }
        data += n;
        size -= std::size_t(n);
    }
    if (!ok && errno == EPIPE) {
        int saved = errno;
        timespec zero{};
        sigtimedwait(&pipe_signal, nullptr, &zero);  // drop the SIGPIPE now pending on us
        errno = saved;
    }
    pthread_sigmask(SIG_SETMASK, &old, nullptr);
    return ok;
}

}  // namespace

VideoWriter::~VideoWriter() {
    if (is_open()) (void)close();
}

Status VideoWriter::open(const std::string& path, int width, int height,
                         const VideoOptions& options) {
    REPRISE_ASSERT(!is_open());
    REPRISE_TRY(check_image_size(width, height, path));
    if (!(options.fps > 0.0) || !std::isfinite(options.fps) || options.fps > 1000.0)
        return Status::error(path + ": frame rate " + number(options.fps) +
                             " is outside (0, 1000]");
    if (options.crf < 0 || options.crf > 51)
        return Status::error(path + ": crf " + std::to_string(options.crf) + " is outside 0..51");

    const int padded_w = width + (width & 1), padded_h = height + (height & 1);
    const std::vector<std::string> args = {
        options.ffmpeg, "-hide_banner",
        "-loglevel",    "error",
        "-f",           "rawvideo",
        "-pix_fmt",     "rgb24",
        "-s",           std::to_string(padded_w) + "x" + std::to_string(padded_h),
        "-r",           number(options.fps),
        "-i",           "-",
        "-c:v",         "libx264",
        "-crf",         std::to_string(options.crf),
        "-pix_fmt",     "yuv420p",
        "-f",           "mp4",
        "-y",           path.starts_with('-') ? "file:" + path : path};
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);

    int pipe_fds[2];
    if (pipe2(pipe_fds, O_CLOEXEC) != 0)
        return Status::error(path + ": cannot create a pipe to ffmpeg: " + std::strerror(errno));
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, pipe_fds[0], STDIN_FILENO);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
    pid_t pid = -1;
    int spawned =
        posix_spawnp(&pid, options.ffmpeg.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(pipe_fds[0]);
    if (spawned != 0) {
        ::close(pipe_fds[1]);
        if (spawned == ENOENT)
            return Status::error(path + ": '" + options.ffmpeg +
                                 "' not found on PATH; video export needs FFmpeg installed");
        return Status::error(path + ": cannot start '" + options.ffmpeg +
                             "': " + std::strerror(spawned));
    }
    path_ = path;
    pid_ = int(pid);
    fd_ = pipe_fds[1];
    width_ = width;
    height_ = height;
    frames_ = 0;
    buffer_.assign(std::size_t(padded_w) * padded_h * 3, 0);
    return {};
}

Status VideoWriter::write(ImageView<const Rgb8> frame) {
    REPRISE_ASSERT(is_open());
    if (frame.width != width_ || frame.height != height_)
        return Status::error(path_ + ": frame " + std::to_string(frames_) + " is " +
                             std::to_string(frame.width) + "x" + std::to_string(frame.height) +
                             ", the video is " + std::to_string(width_) + "x" +
                             std::to_string(height_));
    const int padded_w = width_ + (width_ & 1), padded_h = height_ + (height_ & 1);
    const std::size_t row_bytes = std::size_t(padded_w) * 3;
    for (int y = 0; y < padded_h; ++y) {
        const Rgb8* src = frame.row(std::min(y, height_ - 1));
        uint8_t* dst = buffer_.data() + y * row_bytes;
        std::memcpy(dst, src, std::size_t(width_) * 3);
        if (padded_w != width_) std::memcpy(dst + width_ * 3, src + width_ - 1, 3);
    }
    if (!write_all(fd_, buffer_.data(), buffer_.size())) {
        std::string why = std::strerror(errno);
        const int frame_index = frames_;
        Status closed = close();
        if (!closed.ok())
            return Status::error(closed.message() + " at frame " + std::to_string(frame_index));
        return Status::error(path_ + ": cannot send frame " + std::to_string(frame_index) +
                             " to ffmpeg: " + why);
    }
    ++frames_;
    return {};
}

Status VideoWriter::close() {
    if (!is_open()) return {};
    ::close(fd_);
    fd_ = -1;
    int wait_status = 0;
    pid_t r;
    do r = waitpid(pid_t(pid_), &wait_status, 0);
    while (r < 0 && errno == EINTR);
    pid_ = -1;
    if (r < 0) return Status::error(path_ + ": lost track of ffmpeg: " + std::strerror(errno));
    if (!WIFEXITED(wait_status) || WEXITSTATUS(wait_status) != 0)
        return Status::error(path_ + ": ffmpeg failed (" + exit_text(wait_status) + ")");
    return {};
}

Status write_mp4(const std::string& path, std::span<const ImageView<const Rgb8>> frames,
                 const VideoOptions& options) {
    if (frames.empty()) return Status::error(path + ": no frames to write");
    VideoWriter writer;
    REPRISE_TRY(writer.open(path, frames[0].width, frames[0].height, options));
    for (const ImageView<const Rgb8>& f : frames) REPRISE_TRY(writer.write(f));
    return writer.close();
}

}  // namespace reprise
