#pragma once
// `--range A:B`: the part of a sequence one run of a farm's chunk processes.
#include <cstddef>
#include <string>

#include "reprise/core/status.hpp"

namespace reprise::cli {

// An inclusive range of items (input pairs for fruc, frames for stereo); `all` when not given.
struct InputRange {
    std::size_t first = 0, last = 0;
    bool all = true;
};

// Parses "A:B" (whole numbers, A <= B <= count - 1) where `count` items exist; `what` names them
// in errors ("input pairs", "frames"). Empty text: the whole sequence.
Status parse_input_range(const std::string& text, std::size_t count, const std::string& what,
                         InputRange& range);

}  // namespace reprise::cli
