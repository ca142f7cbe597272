#pragma once
// Non-owning image views and owning images with a typed pixel format.
// Rows are `stride` elements apart; pixel (x, y) has its centre at (x + 0.5, y + 0.5).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "reprise/core/status.hpp"

namespace reprise {

template <class T>
struct ImageView {
    T* data = nullptr;
    int width = 0;
    int height = 0;
    std::ptrdiff_t stride = 0;  // in elements

    T* row(int y) const { return data + y * stride; }
    T& operator()(int x, int y) const { return data[y * stride + x]; }
    bool empty() const { return width <= 0 || height <= 0; }
    std::size_t pixel_count() const { return std::size_t(width) * std::size_t(height); }

    operator ImageView<const T>() const requires(!std::is_const_v<T>) {
        return {data, width, height, stride};
    }
};

// Pixel storage. A buffer of 2 MiB or more is 2 MiB-aligned and advised for transparent huge
// pages (Linux madvise), so that a frame-sized buffer is touched in a few page faults instead of
// thousands (on a virtual machine each one costs microseconds) and reads miss the TLB less.
void* allocate_pixels(std::size_t bytes);
void free_pixels(void* pixels, std::size_t bytes) noexcept;

template <class T>
struct PixelAllocator {
    using value_type = T;
    PixelAllocator() = default;
    template <class U>
    PixelAllocator(const PixelAllocator<U>&) noexcept {}
    T* allocate(std::size_t n) { return static_cast<T*>(allocate_pixels(n * sizeof(T))); }
    void deallocate(T* p, std::size_t n) noexcept { free_pixels(p, n * sizeof(T)); }
    template <class U>
    bool operator==(const PixelAllocator<U>&) const noexcept {
        return true;
    }
};

template <class T>
class Image {
public:
    Image() = default;
    Image(int width, int height, T value = T{}) { assign(width, height, value); }
    Image(const Image&) = default;
    Image& operator=(const Image&) = default;
    // A moved-from image is 0 x 0, so that resizing it to its old size allocates again.
    Image(Image&& other) noexcept
        : pixels_(std::move(other.pixels_)),
          width_(std::exchange(other.width_, 0)),
          height_(std::exchange(other.height_, 0)) {
        other.pixels_.clear();
    }
    Image& operator=(Image&& other) noexcept {
        if (this != &other) {
            pixels_ = std::move(other.pixels_);
            other.pixels_.clear();
            width_ = std::exchange(other.width_, 0);
            height_ = std::exchange(other.height_, 0);
        }
        return *this;
    }

    // A new size gives zero pixels (T{}); the current size keeps them as they are: no
    // reallocation and no clearing, so per-frame code can size its buffers every frame.
    void resize(int width, int height) {
        REPRISE_ASSERT(width >= 0 && height >= 0);
        if (width == width_ && height == height_) return;
        width_ = width;
        height_ = height;
        pixels_.assign(std::size_t(width) * std::size_t(height), T{});
    }
    // Sizes the image and sets every pixel to `value`.
    void assign(int width, int height, T value) {
        resize(width, height);
        fill(value);
    }
    // Sizes the image as the view and copies its pixels (any row stride); an empty view empties it.
    void assign(ImageView<const T> from) {
        if (from.empty()) return clear();
        resize(from.width, from.height);
        for (int y = 0; y < from.height; ++y)
            std::copy_n(from.row(y), from.width, pixels_.data() + std::size_t(y) * width_);
    }
    void fill(T value) { std::fill(pixels_.begin(), pixels_.end(), value); }
    void clear() { resize(0, 0); }

    int width() const { return width_; }
    int height() const { return height_; }
    bool empty() const { return pixels_.empty(); }
    std::size_t pixel_count() const { return pixels_.size(); }

    T* data() { return pixels_.data(); }
    const T* data() const { return pixels_.data(); }
    T& operator()(int x, int y) { return pixels_[std::size_t(y) * width_ + x]; }
    const T& operator()(int x, int y) const { return pixels_[std::size_t(y) * width_ + x]; }

    ImageView<T> view() { return {pixels_.data(), width_, height_, width_}; }
    ImageView<const T> view() const { return {pixels_.data(), width_, height_, width_}; }

    bool operator==(const Image&) const = default;

private:
    std::vector<T, PixelAllocator<T>> pixels_;
    int width_ = 0;
    int height_ = 0;
};

// Largest width or height reprise accepts from files and arguments.
inline constexpr int kMaxImageSide = 16384;

// Checks a size that came from untrusted data; `what` names its origin.
inline Status check_image_size(int width, int height, std::string_view what) {
    if (width <= 0 || height <= 0 || width > kMaxImageSide || height > kMaxImageSide)
        return Status::error(std::string(what) + ": image size " + std::to_string(width) + "x" +
                             std::to_string(height) + " is outside 1.." +
                             std::to_string(kMaxImageSide));
    return {};
}

}  // namespace reprise
