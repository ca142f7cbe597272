#include "reprise/core/memory_limit.hpp"

#include <atomic>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <mutex>

namespace reprise {

namespace {

std::atomic<std::uint64_t> g_limit{kDefaultMemoryLimit};
std::mutex g_hint_mutex;
std::string g_hint = "reprise::set_memory_limit to change";

std::string hint() {
    std::lock_guard lock(g_hint_mutex);
    return g_hint;
}

}  // namespace

std::uint64_t memory_limit() { return g_limit.load(std::memory_order_relaxed); }

void set_memory_limit(std::uint64_t bytes) {
    REPRISE_ASSERT(bytes > 0);
    g_limit.store(bytes, std::memory_order_relaxed);
}

void set_memory_limit_hint(std::string text) {
    std::lock_guard lock(g_hint_mutex);
    g_hint = std::move(text);
}

Status check_memory(std::uint64_t bytes, std::string_view what) {
    const std::uint64_t limit = memory_limit();
    if (bytes <= limit) return {};
    return Status::error(std::string(what) + ": needs " + format_bytes(bytes) + "; limit " +
                         format_bytes(limit) + ", " + hint());
}

Status check_image_memory(int width, int height, std::uint64_t bytes_per_pixel,
                          std::string_view what) {
    REPRISE_ASSERT(width >= 0 && height >= 0);
    const std::uint64_t bytes = std::uint64_t(width) * std::uint64_t(height) * bytes_per_pixel;
    if (bytes <= memory_limit()) return {};
    return check_memory(
        bytes, std::string(what) + " " + std::to_string(width) + "x" + std::to_string(height));
}

std::string format_bytes(std::uint64_t bytes) {
    static constexpr const char* kUnits[] = {"KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
    if (bytes < 1024) return std::to_string(bytes) + (bytes == 1 ? " byte" : " bytes");
    double value = double(bytes);
    int unit = -1;
    while (value >= 1024.0 && unit < 5) value /= 1024.0, ++unit;
    char text[32];
    // Rounded up: a figure never reads smaller than what it stands for.
    const double tenths = std::ceil(value * 10.0 - 1e-9) / 10.0;
    if (tenths == std::floor(tenths))
        std::snprintf(text, sizeof text, "%.0f %s", tenths, kUnits[unit]);
    else
        std::snprintf(text, sizeof text, "%.1f %s", tenths, kUnits[unit]);
    return text;
}

Status parse_bytes(std::string_view text, std::uint64_t& bytes) {
    const std::string quoted = std::string(1, '\'').append(text).append(1, '\'');
    auto bad = [&] {
        return Status::error(quoted + " is not a memory size (e.g. 8G, 512M or bytes)");
    };
    double value = 0.0;
    const char* end = text.data() + text.size();
    auto [rest, ec] = std::from_chars(text.data(), end, value);
    if (ec != std::errc() || rest == text.data() || !std::isfinite(value) || value < 0.0)
        return bad();
    std::string unit(rest, end);
    for (char& c : unit) c = char(std::toupper(static_cast<unsigned char>(c)));
    if (unit.size() > 2 && unit.ends_with("IB"))
        unit.resize(unit.size() - 2);
    else if (unit.size() > 1 && unit.ends_with("B"))
        unit.pop_back();
    double scale = 1.0;
    if (unit == "K")
        scale = 0x1p10;
    else if (unit == "M")
        scale = 0x1p20;
    else if (unit == "G")
        scale = 0x1p30;
    else if (unit == "T")
        scale = 0x1p40;
    else if (!unit.empty() && unit != "B")
        return bad();
    const double total = std::floor(value * scale);
    if (total < 1.0) return Status::error("memory size " + quoted + " must be > 0");
    if (total >= 0x1p63) return Status::error("memory size " + quoted + " is too large");
    bytes = std::uint64_t(total);
    return {};
}

}  // namespace reprise
