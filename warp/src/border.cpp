// The border strip a camera uncovers, continued from the row beside it (fill.hpp).
#include <algorithm>

#include "reprise/warp/fill.hpp"

namespace reprise::warp {

std::size_t continue_border_rows(ImageView<glm::vec4> color, ImageView<float> depth,
                                 ImageView<uint8_t> valid, int max_run) {
    std::size_t filled = 0;
    const int w = color.width;
    const int run = std::max(max_run, 0);
    auto take = [&](int x, int from, int y) {
        color(x, y) = color(from, y);
        if (!depth.empty()) depth(x, y) = depth(from, y);
        valid(x, y) = 1;
    };
    for (int y = 0; y < color.height; ++y) {
        const uint8_t* v = valid.row(y);
        int left = 0, right = w - 1;
        while (left < w && !v[left]) ++left;
        if (left == w) continue;
        while (!v[right]) --right;
        const int x0 = left - std::min(left, run), x1 = right + 1 + std::min(w - 1 - right, run);
        for (int x = x0; x < left; ++x) take(x, left, y);
        for (int x = right + 1; x < x1; ++x) take(x, right, y);
        filled += std::size_t(left - x0) + std::size_t(x1 - right - 1);
    }
    return filled;
}

}  // namespace reprise::warp
