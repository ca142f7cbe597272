#!/usr/bin/env python3
"""reprise from Python, notebook style: render, upconvert 30 -> 60 Hz, measure, encode, write.

Run from the repository after `scripts/build`:
    PYTHONPATH=build/python python3 examples/python_upconvert.py [OUT_DIR]
Each "# %%" cell runs on its own in Jupyter or VS Code as well.
"""
# %% Render a built-in scene at 60 Hz: the even frames are the 30 Hz input, the odd ones the truth.
import sys

import numpy as np

import reprise

out_dir = sys.argv[1] if len(sys.argv) > 1 else "out/python_upconvert"
renderer = reprise.Renderer()
scene = reprise.Scene("pan")
frames_60 = renderer.render_sequence(scene, frames=9, fps=60.0, width=320, height=180)
print(f"rendered {len(frames_60)} frames on {renderer.device}")

# %% Channels are numpy views of the frame's own buffers (no copies).
frame = frames_60[0]
print("colour", frame.color.shape, frame.color.dtype, "depth", frame.depth.shape,
      "motion", frame.motion.shape)
print("mean horizontal motion: %.2f px per 1/60 s" % np.nanmean(frame.motion[..., 0]))

# %% Upconvert the 30 Hz frames to 60 Hz by interpolation.
inputs = [f.copy() for f in frames_60[::2]]
for f in inputs:
    f.fps = 30.0
converter = reprise.FrameRateConverter(factor=2, mode="interpolate", warp="grid", fill="pullpush")
made = converter.convert(inputs)
print("converter counters:", converter.counters)

# %% Made frames against the rendered truth, beside repeating the previous frame.
for k in range(1, len(made), 2):
    truth = reprise.to_display(frames_60[k].color)
    ours = reprise.image_error(truth, reprise.to_display(made[k].color))
    repeated = reprise.psnr(truth, reprise.to_display(frames_60[k - 1].color))
    print(f"frame {k}: PSNR {ours['psnr']:.2f} dB (repetition {repeated:.2f} dB), "
          f"SSIM {ours['ssim']:.4f}, FLIP {ours['flip']:.4f}")

# %% The other eye of the first frame, and the frames through the codec.
right = reprise.synthesize_eye(frames_60[0], ipd=0.064, rendered_eye="left")
stream = reprise.encode_stream(frames_60, qp=28)
decoded = reprise.decode_stream(stream)
print(f"stereo eye {right.width}x{right.height}; codec: {len(stream)} bytes for "
      f"{len(decoded)} frames, PSNR of the last "
      f"{reprise.psnr(reprise.to_display(frames_60[-1].color), reprise.to_display(decoded[-1].color)):.2f} dB")

# %% Write the 60 Hz sequence: reprise's layout, and one frame as Blender reads it.
paths = reprise.write_sequence(out_dir + "/fruc60", made)
reprise.write_frame(out_dir + "/blender_frame.exr", made[1], layout="blender")
print(f"wrote {len(paths)} frames to {out_dir}/fruc60 and {out_dir}/blender_frame.exr")
