#pragma once
// The codec's kernels that have a SIMD version beside their scalar reference, in the same form
// as warp's registry: `reprise bench kernels` times them and tests/test_kernels.cpp checks that
// every SIMD level gives the reference's bits (the codec's encoder and decoder must agree).
#include <span>

#include "reprise/warp/kernel_registry.hpp"

namespace reprise::codec {

std::span<const warp::KernelEntry> kernel_registry();

}  // namespace reprise::codec
