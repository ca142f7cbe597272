#include "reprise/core/image.hpp"

#include <cstdlib>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace reprise {

namespace {

constexpr std::size_t kHugePage = std::size_t(2) << 20;

// Under AddressSanitizer (the sanitizer and fuzzing builds) every buffer is a plain one: huge
// pages there only inflate the resident memory libFuzzer bounds.
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kPlain = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kPlain = true;
#else
constexpr bool kPlain = false;
#endif
#else
constexpr bool kPlain = false;
#endif

}  // namespace

void* allocate_pixels(std::size_t bytes) {
    if (kPlain || bytes < kHugePage) return ::operator new(bytes);
    const std::size_t rounded = (bytes + kHugePage - 1) / kHugePage * kHugePage;
    void* pixels = std::aligned_alloc(kHugePage, rounded);
    if (!pixels) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    madvise(pixels, rounded, MADV_HUGEPAGE);  // advice only: without huge pages, plain ones
#endif
    return pixels;
}

void free_pixels(void* pixels, std::size_t bytes) noexcept {
    if (kPlain || bytes < kHugePage)
        ::operator delete(pixels);
    else
        std::free(pixels);
}

}  // namespace reprise
