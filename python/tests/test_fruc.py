"""Frame-rate upconversion from Python: 30 -> 60 Hz beats repeating frames."""
import numpy as np
import pytest

import reprise
from conftest import psnr


def test_interpolated_frames_beat_repetition(pan_60):
    inputs = [pan_60[0].copy(), pan_60[2].copy(), pan_60[4].copy()]
    for f in inputs:
        f.fps = 30.0
    converter = reprise.FrameRateConverter(factor=2, mode="interpolate", warp="grid")
    out = converter.convert(inputs)
    # The first frame, then (between, frame) for each following one.
    assert len(out) == 5
    assert converter.counters["inputs"] == 3 and converter.counters["outputs"] == 2
    for k in (1, 3):
        made = psnr(pan_60[k], out[k])
        repeated = psnr(pan_60[k], pan_60[k - 1])
        print(f"in-between frame {k}: {made:.2f} dB vs repetition {repeated:.2f} dB")
        assert made > repeated + 2.0
    assert np.array_equal(out[2].color, pan_60[2].color)
    # Each input's silhouettes widened once (the default), or not at all.
    assert converter.counters["silhouette_pixels"] > 0
    kept = reprise.FrameRateConverter(factor=2, widen_silhouettes=False)
    kept.convert(inputs)
    assert kept.counters["silhouette_pixels"] == 0
    # Blended in linear light instead of on the display's scale: another frame, inputs as given.
    linear = reprise.FrameRateConverter(factor=2, perceptual=False).convert(inputs)
    assert not np.array_equal(linear[1].color, out[1].color)
    assert psnr(pan_60[1], linear[1]) > psnr(pan_60[1], pan_60[0]) + 2.0
    assert np.array_equal(linear[2].color, pan_60[2].color)


def test_extrapolation_and_receive(pan_60, renderer):
    converter = reprise.FrameRateConverter(2, mode="extrapolate", fill="andreev")
    converter.send(pan_60[0])
    first = converter.receive()
    beyond = converter.receive()
    assert first is not None and beyond is not None and converter.receive() is None
    assert beyond.color.shape == pan_60[0].color.shape
    # The panning camera uncovers a strip at the border: continued before the fill, or not at all.
    inputs = renderer.render_sequence(reprise.Scene("pan"), frames=3, fps=30.0, width=160, height=90)
    for run in (8, 0):
        ahead = reprise.FrameRateConverter(2, mode="extrapolate", border_run=run)
        ahead.convert(inputs)
        assert (ahead.counters["border_pixels"] > 0) == (run > 0)
    with pytest.raises(ValueError, match="border_run"):
        reprise.FrameRateConverter(2, border_run=-1)


def test_bad_arguments_raise(pan_60):
    with pytest.raises(ValueError):
        reprise.FrameRateConverter(0)
    with pytest.raises(ValueError, match="factor 17: expected 1..16"):
        reprise.FrameRateConverter(17)
    with pytest.raises(ValueError, match="mode"):
        reprise.FrameRateConverter(2, mode="sideways")
    with pytest.raises(ValueError, match="warp 'mesh': expected reverse, splat, grid, grid-bicubic"):
        reprise.FrameRateConverter(2, warp="mesh")
    # The names the command line takes: the bilinear grid too.
    reprise.FrameRateConverter(2, warp="grid-bilinear")
    converter = reprise.FrameRateConverter(2)
    frame = reprise.Frame(np.zeros((8, 8, 4)), depth=np.ones((8, 8)))
    converter.send(frame)
    with pytest.raises(TypeError):
        converter.send(None)
    with pytest.raises(TypeError):
        converter.convert([frame, None])


def test_auto_choice_and_ui_layer(pan_60):
    inputs = [pan_60[0].copy(), pan_60[2].copy(), pan_60[4].copy()]
    ui = np.zeros(inputs[0].color.shape, np.float32)
    ui[4:12, 4:40] = (0.5, 0.5, 0.5, 0.5)
    for i, f in enumerate(inputs):
        f.fps = 30.0
        f.ui = ui * (i + 1) / 3
    converter = reprise.FrameRateConverter(factor=2, warp="auto", fill="auto")
    out = converter.convert(inputs)
    counters = converter.counters
    assert sum(counters["auto_chosen"].values()) == 2
    assert counters["ui_frames"] == 2
    # s = 1/2: the later input's UI, unwarped.
    assert np.array_equal(out[1].ui, inputs[1].ui) and np.array_equal(out[3].ui, inputs[2].ui)


def test_gpu_backend_makes_the_cpus_splat_frames(pan_60):
    inputs = [pan_60[0].copy(), pan_60[2].copy(), pan_60[4].copy()]
    for f in inputs:
        f.fps = 30.0
    # The GPU works in linear light: the CPU's frames are made so to compare them.
    linear = dict(perceptual=False)
    splat = dict(factor=2, warp="splat", refine=False, true_motion=False)
    cpu = reprise.FrameRateConverter(**splat, **linear).convert(inputs)
    gpu = reprise.FrameRateConverter(**splat, backend="gles").convert(inputs)
    assert len(gpu) == len(cpu) == 5
    for k in range(5):
        # The bar for the GPU backend; on llvmpipe the frames are bit-identical.
        assert reprise.psnr(reprise.to_display(gpu[k].color), reprise.to_display(cpu[k].color)) >= 50.0
    # Per output period, as the CPU's, but where its SIMD blend rounds the same-surface test
    # otherwise (at most 0.1 % of the pixels).
    differ = np.any(np.abs(gpu[1].motion - cpu[1].motion) > 1e-4, axis=-1)
    assert differ.mean() <= 0.001
    # Extrapolated on the GPU: the CPU's frames, motion included.
    ahead = dict(factor=2, mode="extrapolate", warp="splat")
    cpu = reprise.FrameRateConverter(**ahead, **linear).convert(inputs)
    gpu = reprise.FrameRateConverter(**ahead, backend="gles").convert(inputs)
    assert len(gpu) == len(cpu) == 6
    for k in range(6):
        assert reprise.psnr(reprise.to_display(gpu[k].color), reprise.to_display(cpu[k].color)) >= 50.0
    assert np.array_equal(gpu[1].motion, cpu[1].motion)
    # True motion (the default) on the GPU too: the CPU's frames.
    cpu = reprise.FrameRateConverter(factor=2, warp="splat", refine=False, **linear).convert(inputs)
    gpu = reprise.FrameRateConverter(factor=2, warp="splat", refine=False,
                                     backend="gles").convert(inputs)
    for k in range(5):
        assert reprise.psnr(reprise.to_display(gpu[k].color), reprise.to_display(cpu[k].color)) >= 50.0
    # The default warp, the grid, without refinement: both sides' cells grown and drawn there.
    cpu = reprise.FrameRateConverter(factor=2, refine=False, **linear).convert(inputs)
    gpu = reprise.FrameRateConverter(factor=2, refine=False, backend="gles").convert(inputs)
    for k in range(5):
        assert reprise.psnr(reprise.to_display(gpu[k].color), reprise.to_display(cpu[k].color)) >= 50.0
    # The defaults, refinement on: its survey and choices on the GPU, the flow on the CPU.
    cpu = reprise.FrameRateConverter(factor=2, **linear).convert(inputs)
    gpu = reprise.FrameRateConverter(factor=2, backend="gles").convert(inputs)
    for k in range(5):
        assert reprise.psnr(reprise.to_display(gpu[k].color), reprise.to_display(cpu[k].color)) >= 50.0
    with pytest.raises(ValueError, match="fill pullpush only"):
        reprise.FrameRateConverter(factor=2, fill="andreev", backend="gles")
    with pytest.raises(ValueError, match="expected cpu or gles"):
        reprise.FrameRateConverter(factor=2, backend="vulkan")
