// The running counts encoder and decoder keep alike.
#include "internal.hpp"

namespace reprise::codec {

void add_stats(StreamStats& total, const StreamStats& f) {
    total.frames += f.frames;
    total.nonfinite += f.nonfinite;
    total.key_frames += f.key_frames;
    total.older_reference += f.older_reference;
    total.header_bits += f.header_bits;
    total.camera_bits += f.camera_bits;
    total.depth_bits += f.depth_bits;
    total.motion_bits += f.motion_bits;
    total.color_bits += f.color_bits;
    total.blocks += f.blocks;
    total.blocks_skipped += f.blocks_skipped;
    total.intra_blocks += f.intra_blocks;
    total.motion_residual_pixels += f.motion_residual_pixels;
    total.motion_models += f.motion_models;
    total.motion_own_pixels += f.motion_own_pixels;
    total.motion_objects += f.motion_objects;
    total.depth_zero_blocks += f.depth_zero_blocks;
    total.depth_plane_blocks += f.depth_plane_blocks;
    total.depth_parts += f.depth_parts;
    total.motion_parts += f.motion_parts;
    total.revealed_pixels += f.revealed_pixels;
    total.cameras_fitted += f.cameras_fitted;
    total.ms.input += f.ms.input;
    total.ms.convert += f.ms.convert;
    total.ms.objects += f.ms.objects;
    total.ms.reproject += f.ms.reproject;
    total.ms.depth += f.ms.depth;
    total.ms.motion += f.ms.motion;
    total.ms.predict += f.ms.predict;
    total.ms.color += f.ms.color;
}

}  // namespace reprise::codec
