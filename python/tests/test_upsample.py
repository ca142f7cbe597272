"""Spatio-temporal upsampling from Python, on the CPU and the GPU."""
import numpy as np
import pytest

import reprise


def every_other_pixel(frame):
    """Every other pixel of every other row: low pixel (u, v) is full pixel (2u, 2v), which the
    upsampler's convention places at jitter (-0.5, -0.5) full pixels."""
    return reprise.Frame(np.ascontiguousarray(frame.color[::2, ::2]))


def test_upsampling_beats_copying_and_the_gpu_makes_the_cpus_frames(pan_60):
    cpu, gpu = reprise.Upsampler(), reprise.Upsampler(backend="gles")
    for k, full in enumerate(pan_60):
        low = every_other_pixel(full)
        made, stats = cpu.upsample(low, full, jitter=(-0.5, -0.5))
        on_gpu, gpu_stats = gpu.upsample(low, full, jitter=(-0.5, -0.5))
        assert made.color.shape == full.color.shape
        # The bar for the GPU backend; on llvmpipe the frames are bit-identical.
        assert reprise.psnr(reprise.to_display(on_gpu.color),
                            reprise.to_display(made.color)) >= 50.0
        assert gpu_stats["history_used"] == stats["history_used"]
        if k > 0:
            assert stats["history_used"] > 0
    truth = reprise.to_display(pan_60[-1].color)
    nearest = np.repeat(np.repeat(pan_60[-1].color[::2, ::2], 2, axis=0), 2, axis=1)
    nearest = nearest[:truth.shape[0], :truth.shape[1]]
    ours = reprise.psnr(reprise.to_display(made.color), truth)
    copied = reprise.psnr(reprise.to_display(nearest), truth)
    print(f"upsampled {ours:.2f} dB, pixels repeated {copied:.2f} dB")
    assert ours > copied + 1.0


def test_bad_upsampling_input_raises(pan_60):
    with pytest.raises(ValueError, match="expected cpu or gles"):
        reprise.Upsampler(backend="metal")
    with pytest.raises(ValueError, match="history_weight"):
        reprise.Upsampler(history_weight=2.0)
    up = reprise.Upsampler()
    with pytest.raises(ValueError, match="depth"):
        up.upsample(every_other_pixel(pan_60[0]), reprise.Frame(np.zeros((4, 4, 4))))
    big = reprise.Frame(np.zeros((pan_60[0].height * 2, pan_60[0].width, 4)))
    with pytest.raises(ValueError, match="larger"):
        up.upsample(big, pan_60[0])


def test_upsampling_past_the_memory_limit_is_refused(pan_60):
    reprise.set_max_memory("1M")
    try:
        with pytest.raises(reprise.Error, match="upsample"):
            reprise.Upsampler().upsample(every_other_pixel(pan_60[0]), pan_60[0])
    finally:
        reprise.set_max_memory("4G")
