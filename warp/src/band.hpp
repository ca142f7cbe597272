#pragma once
// Target rows drawn a band at a time by the forward warps (splat, grid): each thread draws into a
// scratch band that stays in its cache, then writes the band out with streaming stores.
#include <cstddef>
#include <vector>

#include "reprise/warp/splat.hpp"

namespace reprise::warp {

// Target rows [y0, y0 + view height) as a warp sees them. While drawing, `covered` may hold any
// non-zero value where something landed.
struct Band {
    WarpTarget view;
    int y0;
};

// What every forward warp asserts of its inputs: the source's depth and motion the size of its
// colour, the target's channels the size of its colour (motion may be empty).
void check_warp_inputs(const GBufferView& source, const WarpTarget& target);

// Scratch rows with room for vector kernels to read a few pixels past the last.
template <class T>
ImageView<T> scratch_rows(std::vector<T>& pixels, int width, int rows) {
    const std::size_t n = std::size_t(width) * std::size_t(rows) + 4;
    if (pixels.size() < n) pixels.resize(n);
    return {pixels.data(), width, rows, width};
}

// splat() that calls refine(band, context) on each band of the target after drawing it and
// before writing it out (its `covered` then non-zero where something landed).
using BandRefine = void (*)(const Band& band, const void* context);
std::size_t splat_refined(const GBufferView& source, float factor, const WarpTarget& target,
                          const SplatOptions& options, BandRefine refine, const void* context);

// Depth +inf, nothing covered.
void clear_band(const Band& band);
// In place: covered becomes 0/1, depths at or beyond `background_from` +inf, colour and motion
// 0 where nothing landed. Returns the covered count; adds to `nonfinite`, when given, the covered
// pixels whose colour has a NaN or infinite channel.
std::size_t finish_band(const Band& band, float background_from, std::size_t* nonfinite = nullptr,
                        bool keep_stretched = false);
// The same, written from a scratch band to its rows of `target`.
std::size_t copy_band(const Band& scratch, const WarpTarget& target, float background_from,
                      std::size_t* nonfinite = nullptr, bool keep_stretched = false);

}  // namespace reprise::warp
