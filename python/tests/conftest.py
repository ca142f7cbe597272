"""Shared fixtures: one renderer and a few small rendered frames for the whole session."""
import numpy as np
import pytest

import reprise

SIZE = dict(width=160, height=96)


@pytest.fixture(scope="session")
def renderer():
    return reprise.Renderer()


@pytest.fixture(scope="session")
def pan_60(renderer):
    """Five frames of the built-in 'pan' scene at 60 Hz (frames 0, 2, 4 are the 30 Hz input)."""
    scene = reprise.Scene("pan")
    return renderer.render_sequence(scene, frames=5, fps=60.0, **SIZE)


def display(frame):
    return reprise.to_display(frame.color)


def psnr(a, b):
    return reprise.psnr(display(a), display(b))


@pytest.fixture
def small_frame():
    rng = np.random.default_rng(1)
    color = rng.random((6, 8, 4), dtype=np.float32)
    depth = rng.uniform(1.0, 10.0, (6, 8)).astype(np.float32)
    depth[0, 0] = np.inf
    motion = rng.uniform(-2, 2, (6, 8, 2)).astype(np.float32)
    normal = np.tile(np.array([0, 0, 1], np.float32), (6, 8, 1))
    ids = np.arange(48, dtype=np.uint32).reshape(6, 8)
    return reprise.Frame(color, depth=depth, motion=motion, normal=normal, id=ids, fps=24.0)
