// The last error, the ABI rule and the checks every entry point shares (reprise.h).
#include "plumbing.hpp"

#include <cmath>
#include <cstdio>
#include <mutex>

#include "reprise/core/memory_limit.hpp"

namespace reprise::capi {
namespace {
thread_local char last_error[1024] = "";
}  // namespace

reprise_status fail(reprise_status status, const char* function, const char* message) noexcept {
    if (function)
        std::snprintf(last_error, sizeof last_error, "%s: %s", function, message);
    else
        std::snprintf(last_error, sizeof last_error, "%s", message);
    return status;
}

reprise_status check_abi(const char* function, uint32_t abi_version) {
    const uint32_t major = abi_version >> 16, minor = abi_version & 0xffffu;
    if (major == REPRISE_ABI_VERSION_MAJOR && minor <= REPRISE_ABI_VERSION_MINOR) return REPRISE_OK;
    return fail(REPRISE_ERROR_ABI_MISMATCH, function,
                "abi_version " + std::to_string(major) + "." + std::to_string(minor) +
                    " (the caller's reprise.h) does not match the library's " +
                    std::to_string(REPRISE_ABI_VERSION_MAJOR) + "." +
                    std::to_string(REPRISE_ABI_VERSION_MINOR) +
                    ": the major must be equal and the minor not newer");
}

void name_the_memory_setter() {
    static std::once_flag once;
    std::call_once(once, [] { set_memory_limit_hint("reprise_set_max_memory to change"); });
}

reprise_status check_pointer(const char* function, const void* pointer, const char* name) {
    if (pointer) return REPRISE_OK;
    return fail(REPRISE_ERROR_INVALID_ARGUMENT, function, std::string(name) + " is NULL");
}

reprise_status check_struct_size(const char* function, const char* name, std::size_t given,
                                 std::span<const std::size_t> sizes) {
    for (const std::size_t size : sizes)
        if (given == size) return REPRISE_OK;
    std::string taken = "this library's " + std::to_string(sizes.back());
    for (std::size_t i = 0; i + 1 < sizes.size(); ++i)
        taken += (i == 0 ? " or an older minor's " : ", ") + std::to_string(sizes[i]);
    return fail(REPRISE_ERROR_ABI_MISMATCH, function,
                std::string(name) + " " + std::to_string(given) + " is not " + taken +
                    " bytes: the caller was built against another reprise.h");
}

reprise_status check_range(const char* function, const char* field, double value, double lo,
                           double hi) {
    if (value >= lo && value <= hi) return REPRISE_OK;  // false for NaN
    char message[256];
    std::snprintf(message, sizeof message, "%s %g is outside %g..%g", field, value, lo, hi);
    return fail(REPRISE_ERROR_INVALID_ARGUMENT, function, message);
}

reprise_status check_flag(const char* function, const char* field, int32_t value) {
    if (value == 0 || value == 1) return REPRISE_OK;
    return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                std::string(field) + " " + std::to_string(value) + " is neither 0 nor 1");
}

}  // namespace reprise::capi

using namespace reprise::capi;

extern "C" {

uint32_t reprise_abi_version(void) { return REPRISE_ABI_VERSION; }

const char* reprise_status_name(reprise_status status) {
    switch (status) {
        case REPRISE_OK:
            return "REPRISE_OK";
        case REPRISE_NEED_MORE:
            return "REPRISE_NEED_MORE";
        case REPRISE_ERROR_INVALID_ARGUMENT:
            return "REPRISE_ERROR_INVALID_ARGUMENT";
        case REPRISE_ERROR_ABI_MISMATCH:
            return "REPRISE_ERROR_ABI_MISMATCH";
        case REPRISE_ERROR_BUFFER_TOO_SMALL:
            return "REPRISE_ERROR_BUFFER_TOO_SMALL";
        case REPRISE_ERROR_INVALID_DATA:
            return "REPRISE_ERROR_INVALID_DATA";
        case REPRISE_ERROR_OUT_OF_MEMORY:
            return "REPRISE_ERROR_OUT_OF_MEMORY";
        case REPRISE_ERROR_INTERNAL:
            return "REPRISE_ERROR_INTERNAL";
        default:
            return "unknown status";
    }
}

const char* reprise_last_error(void) { return reprise::capi::last_error; }

reprise_status reprise_set_max_memory(uint64_t bytes) {
    const char* function = "reprise_set_max_memory";
    return guarded(function, [&] {
        if (bytes == 0) return fail(REPRISE_ERROR_INVALID_ARGUMENT, function, "bytes is 0");
        name_the_memory_setter();
        reprise::set_memory_limit(bytes);
        return reprise_status(REPRISE_OK);
    });
}

uint64_t reprise_max_memory(void) { return reprise::memory_limit(); }

}  // extern "C"
