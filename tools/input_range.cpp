#include "input_range.hpp"

#include <charconv>

namespace reprise::cli {

namespace {

bool parse_index(const std::string& text, std::size_t& value) {
    if (text.empty()) return false;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    return ec == std::errc() && end == text.data() + text.size();
}

}  // namespace

Status parse_input_range(const std::string& text, std::size_t count, const std::string& what,
                         InputRange& range) {
    range = {};
    if (text.empty()) return {};
    // Built by appending: GCC 12 warns falsely (-Wrestrict) on "literal" + std::string here.
    std::string message = "--range ";
    message += text;
    const std::size_t colon = text.find(':');
    std::size_t a = 0, b = 0;
    if (colon == std::string::npos || !parse_index(text.substr(0, colon), a) ||
        !parse_index(text.substr(colon + 1), b)) {
        message += ": expected A:B, two whole numbers (";
        message += what;
        message += " A to B, counted from 0)";
        return Status::error(message);
    }
    if (a > b) {
        message += ": A (" + std::to_string(a);
        message += ") is after B (" + std::to_string(b);
        message += ")";
        return Status::error(message);
    }
    if (count == 0 || b >= count) {
        message += ": the sequence has " + std::to_string(count);
        message += " " + what;
        if (count > 0) message += " (0:" + std::to_string(count - 1) + ")";
        return Status::error(message);
    }
    range = {.first = a, .last = b, .all = false};
    return {};
}

}  // namespace reprise::cli
