"""Memory bounded before it is spent: estimates checked against reprise.set_max_memory."""
import time

import numpy as np
import pytest

import reprise


@pytest.fixture
def limit():
    """Restores the default limit after a test that changes it."""
    before = reprise.max_memory()
    yield
    reprise.set_max_memory(before)


def test_default_limit_is_4_gib():
    assert reprise.max_memory() == 4 << 30


def test_flip_refuses_a_huge_ppd_quickly():
    image = np.zeros((16, 16, 3), np.float32)
    start = time.monotonic()
    with pytest.raises(reprise.Error, match=r"10000\]"):
        reprise.flip(image, image, pixels_per_degree=1e7)
    assert time.monotonic() - start < 1.0
    # The same bound as the CLI's --ppd: 10000 itself is accepted.
    assert reprise.flip(image, image, pixels_per_degree=1e4) == 0.0


def test_flip_checks_its_kernels_against_the_limit(limit):
    image = np.zeros((16, 16, 3), np.float32)
    reprise.set_max_memory("1M")
    with pytest.raises(reprise.Error, match=r"needs .*; limit 1 MiB, reprise.set_max_memory"):
        reprise.flip(image, image, pixels_per_degree=1e4)
    assert reprise.flip(image, image) == 0.0


def test_lowering_the_limit_makes_a_render_refuse(renderer, limit):
    scene = reprise.Scene("pan")
    reprise.set_max_memory(1 << 20)
    assert reprise.max_memory() == 1 << 20
    with pytest.raises(reprise.Error, match=r"render 160x96: needs [0-9.]+ MiB; limit 1 MiB"):
        renderer.render(scene, width=160, height=96)
    reprise.set_max_memory("64M")
    assert renderer.render(scene, width=160, height=96).color.shape == (96, 160, 4)


def test_a_huge_render_is_refused_at_the_default_limit(renderer):
    with pytest.raises(reprise.Error, match=r"render 8192x8192: needs .* GiB; limit 4 GiB"):
        renderer.render(reprise.Scene("pan"), width=8192, height=8192)


def test_bad_limits_raise_value_error():
    for bad in (0, -5, "lots", "12Q"):
        with pytest.raises(ValueError):
            reprise.set_max_memory(bad)
    assert reprise.max_memory() == 4 << 30


def test_fruc_and_encode_refuse_beyond_the_limit(pan_60, limit):
    reprise.set_max_memory("1M")
    with pytest.raises(reprise.Error, match=r"fruc 160x96: needs [0-9.]+ MiB; limit 1 MiB"):
        reprise.FrameRateConverter(factor=2, mode="interpolate").convert(pan_60[:2])
    with pytest.raises(reprise.Error, match=r"encode 160x96: needs [0-9.]+ MiB; limit 1 MiB"):
        reprise.encode_stream(pan_60[:2], qp=28)
    reprise.set_max_memory("64M")
    assert len(reprise.encode_stream(pan_60[:2], qp=28)) >= 2
