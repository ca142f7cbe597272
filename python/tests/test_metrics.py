"""PSNR, SSIM and FLIP on numpy display images."""
import math

import numpy as np
import pytest

import reprise


def test_known_values():
    ref = np.zeros((16, 16, 3), np.float32)
    test = np.full((16, 16, 3), 0.1, np.float32)
    assert reprise.psnr(ref, ref) == math.inf
    assert reprise.psnr(ref, test) == pytest.approx(20.0, abs=1e-4)
    assert reprise.ssim(test, test) == pytest.approx(1.0)
    assert reprise.flip(ref, ref) == 0.0
    errors = reprise.image_error(ref, test)
    assert errors["psnr"] == pytest.approx(20.0, abs=1e-4) and errors["flip"] > 0.0


def test_layouts_and_masks():
    rng = np.random.default_rng(3)
    ref = rng.random((20, 30, 3), dtype=np.float32)
    test = ref.copy()
    test[:, 15:] = 0.0
    rgba = np.concatenate([test, np.ones((20, 30, 1), np.float32)], axis=2)
    # A strided view and float64 give the same answer as the packed float32 array.
    assert reprise.psnr(ref, rgba[..., :3]) == reprise.psnr(ref, test)
    assert reprise.psnr(ref.astype(np.float64), test) == reprise.psnr(ref, test)
    left = np.zeros((20, 30), bool)
    left[:, :15] = True
    assert reprise.psnr(ref, test, mask=left) == math.inf
    assert reprise.psnr(ref, test, mask=left.astype(np.int64) * 7) == math.inf
    mean, error_map = reprise.flip(ref, test, error_map=True)
    assert error_map.shape == (20, 30)
    assert error_map[:, :10].mean() < 0.1 * error_map[:, 15:].mean()
    assert mean == pytest.approx(error_map.mean(), rel=1e-4)


def test_to_display():
    linear = np.array([[[0.0, 1.0, 2.0, 0.5], [0.0031308, 0.5, -1.0, 1.0]]], np.float32)
    display = reprise.to_display(linear)
    assert display.shape == (1, 2, 3)
    assert np.allclose(display[0, 0], [0.0, 1.0, 1.0]) and display[0, 1, 2] == 0.0
    assert display[0, 1, 1] == pytest.approx(0.7354, abs=1e-3)


@pytest.mark.parametrize("test, error", [
    (np.zeros((8, 8, 3), np.int32), TypeError),
    (np.zeros((8, 9, 3), np.float32), ValueError),
    (np.zeros((8, 8, 4), np.float32), ValueError),
    (np.full((8, 8, 3), np.nan, np.float32), ValueError),
    (np.zeros((0, 8, 3), np.float32), ValueError),
])
def test_bad_images_raise(test, error):
    with pytest.raises(error):
        reprise.psnr(np.zeros((8, 8, 3), np.float32), test)


def test_bad_masks_raise():
    image = np.zeros((8, 8, 3), np.float32)
    with pytest.raises(ValueError):
        reprise.ssim(image, image, mask=np.ones((4, 4), bool))
    with pytest.raises(TypeError):
        reprise.flip(image, image, mask=np.ones((8, 8), np.float32))
    with pytest.raises(reprise.Error):  # core's check_flip_ppd, shared with the CLI's --ppd
        reprise.flip(image, image, pixels_per_degree=0.0)
