"""NaN and infinities written through the numpy views after construction: the library repairs
them at the door (colour: holes; depth NaN/-inf and motion: unknown), counts them, and nothing
non-finite comes out of fruc, the stereo eye or the codec."""
import numpy as np
import pytest

import reprise


def spoil(frame, seed):
    """NaN, +inf, -inf in ~5 % of the colour and motion pixels (through the views)."""
    rng = np.random.default_rng(seed)
    h, w = frame.color.shape[:2]
    counts = {}
    for name, view in (("color", frame.color), ("motion", frame.motion)):
        mask = rng.random((h, w)) < 0.05
        values = rng.choice(np.array([np.nan, np.inf, -np.inf], np.float32), size=int(mask.sum()))
        view[mask, 0] = values
        counts[name] = int(mask.sum())
    return counts


def assert_finite(frame):
    assert np.isfinite(frame.color).all()
    if frame.motion is not None:
        assert np.isfinite(frame.motion).all()
    if frame.depth is not None:
        assert not np.isnan(frame.depth).any() and not (frame.depth == -np.inf).any()


@pytest.mark.parametrize("mode", ["interpolate", "extrapolate"])
@pytest.mark.parametrize("warp", ["reverse", "splat", "grid", "auto"])
def test_fruc_output_is_finite(pan_60, mode, warp):
    inputs = [pan_60[k].copy() for k in (0, 2, 4)]
    want = {"color": 0, "motion": 0}
    for i, f in enumerate(inputs):
        f.fps = 30.0
        for name, n in spoil(f, i).items():
            want[name] += n
    assert not np.isfinite(inputs[1].color).all()  # the views wrote through
    converter = reprise.FrameRateConverter(factor=2, mode=mode, warp=warp)
    out = converter.convert(inputs)
    assert len(out) == (5 if mode == "interpolate" else 6)
    for f in out:
        assert_finite(f)
    seen = converter.counters["nonfinite"]
    assert seen["color"] == want["color"] and seen["motion"] == want["motion"]
    assert seen["frames"] == 3


def test_synthesize_eye_and_codec_output_is_finite(pan_60):
    frame = pan_60[1].copy()
    spoil(frame, 5)
    frame.depth[::17, ::13] = np.nan
    assert_finite(reprise.synthesize_eye(frame, ipd=0.064, rendered_eye="left"))
    for f in reprise.decode_stream(reprise.encode_stream([frame, pan_60[2]])):
        assert_finite(f)
