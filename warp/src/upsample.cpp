// Spatio-temporal upsampling (Herzog et al. 2010); equations in upsample.hpp.
#include "reprise/warp/upsample.hpp"

namespace reprise::warp {

SpatioTemporalUpsampler::SpatioTemporalUpsampler(UpsampleOptions options) : options_(options) {}

void SpatioTemporalUpsampler::reset() { has_history_ = false; }

}  // namespace reprise::warp
