#pragma once
// What every C entry point shares: this thread's last error, the guard that keeps C++
// exceptions from crossing the C boundary, and the checks of the ABI version and of the
// caller's option structs.
#include <array>
#include <cstddef>
#include <cstring>
#include <exception>
#include <memory>
#include <new>
#include <span>
#include <string>

#include "reprise.h"

namespace reprise::capi {

// Records "function: message" as this thread's last error and returns `status`.
reprise_status fail(reprise_status status, const char* function, const char* message) noexcept;
inline reprise_status fail(reprise_status status, const char* function,
                           const std::string& message) noexcept {
    return fail(status, function, message.c_str());
}

// Runs `body` (returning a reprise_status); every exception becomes a status with a message.
// A call that succeeds leaves the last error empty.
template <class Body>
reprise_status guarded(const char* function, Body&& body) noexcept {
    try {
        const reprise_status status = body();
        if (status >= 0) fail(status, nullptr, "");
        return status;
    } catch (const std::bad_alloc&) {
        return fail(REPRISE_ERROR_OUT_OF_MEMORY, function, "out of memory");
    } catch (const std::exception& e) {
        return fail(REPRISE_ERROR_INTERNAL, function, e.what());
    } catch (...) {
        return fail(REPRISE_ERROR_INTERNAL, function, "unknown exception");
    }
}

// Returns from the calling function when a check gave an error.
#define REPRISE_CAPI_TRY(expr)                               \
    do {                                                     \
        const reprise_status capi_status_ = (expr);          \
        if (capi_status_ != REPRISE_OK) return capi_status_; \
    } while (0)

reprise_status check_abi(const char* function, uint32_t abi_version);
// Once per process: the library's refusals name reprise_set_max_memory as the way to raise the
// memory limit.
void name_the_memory_setter();
reprise_status check_pointer(const char* function, const void* pointer, const char* name);
// Checks that a struct the caller filled has a struct_size this library takes: one of `sizes`,
// the struct's size in each minor that changed it, oldest first (the last: this library's).
reprise_status check_struct_size(const char* function, const char* name, std::size_t given,
                                 std::span<const std::size_t> sizes);

// The struct_size values taken for each options struct, one per minor that changed it, oldest
// first; the fields past an older one keep their defaults.
template <class Options>
inline constexpr std::array<std::size_t, 1> kSizes = {sizeof(Options)};
template <>
inline constexpr std::array<std::size_t, 3> kSizes<reprise_converter_options> = {
    offsetof(reprise_converter_options, widen_silhouettes),  // minor 1
    offsetof(reprise_converter_options, perceptual),         // minor 2
    sizeof(reprise_converter_options)};
template <>
inline constexpr std::array<std::size_t, 3> kSizes<reprise_stereo_options> = {
    offsetof(reprise_stereo_options, widen_silhouettes),  // minor 1
    offsetof(reprise_stereo_options, perceptual),         // minor 2
    sizeof(reprise_stereo_options)};

// reprise_*_options_init: `defaults` with struct_size set, into the caller's struct.
template <class Options>
reprise_status init_options(const char* function, Options* options, std::size_t struct_size,
                            Options defaults) {
    return guarded(function, [&] {
        REPRISE_CAPI_TRY(check_pointer(function, options, "options"));
        REPRISE_CAPI_TRY(check_struct_size(function, "struct_size", struct_size, kSizes<Options>));
        defaults.struct_size = uint32_t(struct_size);
        std::memcpy(static_cast<void*>(options), &defaults, struct_size);
        return reprise_status(REPRISE_OK);
    });
}

// A create's common checks: the ABI version, the handle out-pointer and the options struct
// (NULL: the defaults).
template <class Options, class Handle>
reprise_status check_create(const char* function, uint32_t abi_version, const Options* given,
                            Options& options, Handle** handle) {
    REPRISE_CAPI_TRY(check_pointer(function, handle, "the handle's out-pointer"));
    *handle = nullptr;
    REPRISE_CAPI_TRY(check_abi(function, abi_version));
    name_the_memory_setter();
    if (given) {
        REPRISE_CAPI_TRY(check_struct_size(function, "options->struct_size", given->struct_size,
                                           kSizes<Options>));
        std::memcpy(static_cast<void*>(&options), given, given->struct_size);
    }
    return REPRISE_OK;
}

// A create: the common checks, then `configure(options, handle)` on a new handle, which is
// handed out only when that succeeds.
template <class Handle, class Options, class Configure>
reprise_status create_handle(const char* function, uint32_t abi_version, const Options* given,
                             Options options, Handle** handle, Configure&& configure) {
    return guarded(function, [&] {
        REPRISE_CAPI_TRY(check_create(function, abi_version, given, options, handle));
        auto made = std::make_unique<Handle>();
        REPRISE_CAPI_TRY(configure(options, *made));
        *handle = made.release();
        return reprise_status(REPRISE_OK);
    });
}

// A call on a handle: `body(*handle)` after checking it is not NULL (named `name`).
template <class Handle, class Body>
reprise_status with_handle(const char* function, Handle* handle, const char* name, Body&& body) {
    return guarded(function, [&] {
        REPRISE_CAPI_TRY(check_pointer(function, handle, name));
        return reprise_status(body(*handle));
    });
}

// Checks `value` in [lo, hi]; the message names `field`.
reprise_status check_range(const char* function, const char* field, double value, double lo,
                           double hi);
reprise_status check_flag(const char* function, const char* field, int32_t value);

}  // namespace reprise::capi
