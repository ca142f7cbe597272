"""The renderer (built-in scenes and glTF files) and the codec from Python."""
import os

import numpy as np
import pytest

import reprise
from conftest import SIZE, psnr

BOX = "/usr/share/assimp/models/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb"


def test_builtin_scene_frames(pan_60):
    names = [name for name, _ in reprise.builtin_scenes()]
    assert "pan" in names and "fence" in names
    frame = pan_60[1]
    assert frame.color.shape == (96, 160, 4) and frame.fps == 60.0
    assert np.isfinite(frame.depth).any() and np.isinf(frame.depth).any()
    # The camera pans sideways: motion is mostly horizontal and nonzero.
    moving = np.abs(frame.motion[..., 0]) > 0.1
    assert moving.mean() > 0.5
    assert frame.camera.time == pytest.approx(1 / 60)


@pytest.mark.skipif(not os.path.exists(BOX), reason="assimp-testmodels not installed")
def test_gltf_scene(renderer):
    scene = reprise.Scene(BOX, camera="orbit:speed=1")
    frame = renderer.render(scene, frame=3, **SIZE)
    assert (frame.id > 0).mean() > 0.05


def test_bad_scenes_raise(renderer, tmp_path):
    with pytest.raises(reprise.Error, match="nothing"):
        reprise.Scene(str(tmp_path / "nothing.glb"))
    broken = tmp_path / "broken.gltf"
    broken.write_text('{"asset": {"version": "2.0"}, "buffers": [{"uri": "../../etc/passwd", '
                      '"byteLength": 10}]}')
    with pytest.raises(reprise.Error, match="broken.gltf"):
        reprise.Scene(str(broken))
    with pytest.raises(reprise.Error):
        reprise.Scene("pan", camera="spiral")
    with pytest.raises(reprise.Error):
        renderer.render(reprise.Scene("pan"), width=0)
    with pytest.raises(ValueError):
        renderer.render(reprise.Scene("pan"), fps=0.0)


def test_codec_round_trip(pan_60):
    encoder = reprise.Encoder(qp=24)  # depth="view": to the reprojection bound
    lossless = reprise.Encoder(qp=24, depth="lossless")
    decoder, exact = reprise.Decoder(), reprise.Decoder()
    for i, frame in enumerate(pan_60[:3]):
        packet = encoder.encode(frame)
        info = reprise.inspect_packet(packet)
        assert info["frame"] == i and info["key"] == (i == 0)
        decoded = decoder.decode(packet)
        # The decoder's output is the encoder's reconstruction, bit for bit.
        assert np.array_equal(decoded.color, encoder.reconstruction.color)
        assert np.array_equal(decoded.depth, encoder.reconstruction.depth)
        assert np.array_equal(np.isinf(decoded.depth), np.isinf(frame.depth))  # background exact
        assert psnr(frame, decoded) > 30.0
        assert np.array_equal(exact.decode(lossless.encode(frame)).depth, frame.depth)
    assert encoder.stats["frames"] == 3 and encoder.stats["key_frames"] == 1
    assert encoder.stats["depth_bits"] < 0.25 * lossless.stats["depth_bits"]


def test_codec_streams_and_bad_packets(pan_60):
    stream = reprise.encode_stream(pan_60[:2], qp=30)
    frames = reprise.decode_stream(stream)
    assert len(frames) == 2 and frames[1].color.shape == pan_60[1].color.shape
    with pytest.raises(reprise.Error):
        reprise.decode_stream(stream[:-5])
    decoder = reprise.Decoder()
    packet = bytearray(reprise.Encoder().encode(pan_60[0]))
    packet[len(packet) // 2] ^= 0xFF
    with pytest.raises(reprise.Error):
        decoder.decode(packet)
    with pytest.raises(reprise.Error):
        decoder.decode(b"\x00" * 3)
    assert decoder.decode(reprise.Encoder().encode(pan_60[0])) is not None  # still usable
    with pytest.raises(TypeError):
        decoder.decode(np.zeros(4, np.float32))
    with pytest.raises(ValueError):
        reprise.Encoder(qp=99)


def test_anti_aliasing_changes_colour_only(renderer):
    scene = reprise.Scene("fence", camera="pan")
    single = renderer.render(scene, frame=2, aa=1, **SIZE)
    four = renderer.render(scene, frame=2, aa=4, **SIZE)
    np.testing.assert_array_equal(single.depth, four.depth)
    np.testing.assert_array_equal(single.motion, four.motion)
    # Edge pixels take a share of each surface: colour moves on the fence's edges, not inside.
    changed = np.abs(four.color - single.color).max(axis=2) > 1e-3
    assert 0.01 < changed.mean() < 0.6
    with pytest.raises(ValueError, match="aa must be"):
        renderer.render(scene, aa=3, **SIZE)
