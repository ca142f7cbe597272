#pragma once
// One process-wide bound on what a call may allocate. Calls estimate what they need before
// allocating and refuse with the figure, instead of growing until an allocation fails halfway.
#include <cstdint>
#include <string>
#include <string_view>

#include "reprise/core/status.hpp"

namespace reprise {

inline constexpr std::uint64_t kDefaultMemoryLimit = std::uint64_t(4) << 30;  // 4 GiB

std::uint64_t memory_limit();
// `bytes` > 0; thread-safe, takes effect for calls that start afterwards.
void set_memory_limit(std::uint64_t bytes);
// How the user raises the limit, ending every refusal: "--max-memory to change" in the CLI,
// the Python setter in Python.
void set_memory_limit_hint(std::string hint);

// "WHAT: needs 6.1 GiB; limit 4 GiB, --max-memory to change" when `bytes` exceeds the limit.
Status check_memory(std::uint64_t bytes, std::string_view what);

// The same for a working set of `bytes_per_pixel` over a width x height image, named
// "WHAT WxH"; allocates nothing when it passes (per-frame paths).
Status check_image_memory(int width, int height, std::uint64_t bytes_per_pixel,
                          std::string_view what);

// "6.1 GiB", "512 MiB", "3 KiB", "12 bytes" (binary units, one decimal where it is not whole).
std::string format_bytes(std::uint64_t bytes);

// "8G", "512M", "64K", "1.5GiB", "4096" (bytes); units are binary, 'B' and 'iB' optional.
Status parse_bytes(std::string_view text, std::uint64_t& bytes);

}  // namespace reprise
