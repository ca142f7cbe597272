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
    assert frame.camera.cut is False  # a path knows no cut came


def test_the_renderer_marks_the_cut(renderer):
    frames = renderer.render_sequence(reprise.Scene("cut"), 3, start=14, width=32, height=18)
    assert [f.camera.cut for f in frames] == [False, True, False]  # the shot changes at 0.5 s


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
    # Where the depth bits go: the parts add up to the section less its few header bytes.
    parts = encoder.stats["depth_parts"]
    assert parts["key"] > 0 and decoder.stats["depth_parts"]["key"] == 0
    assert 0.9 * encoder.stats["depth_bits"] < sum(parts.values()) <= encoder.stats["depth_bits"] + 32
    # Milliseconds by stage: the inter frames' shared stages ran on both sides.
    for stats in (encoder.stats, decoder.stats):
        assert stats["ms"]["reproject"] > 0 and stats["ms"]["predict"] > 0, stats["ms"]
    assert decoder.stats["ms"]["objects"] == 0


def test_codec_8bit_srgb_in_and_out(pan_60):
    """Colour as 8-bit sRGB display values both ways: the same codes as linear light."""
    encoder, linear, display = reprise.Encoder(qp=24), reprise.Decoder(), reprise.Decoder(display=True)
    again_linear, again_display = reprise.Encoder(qp=24), reprise.Encoder(qp=24)
    for frame in pan_60[:3]:
        packet = encoder.encode(frame)
        decoded = linear.decode(packet)
        shown_frame, rgba = display.decode_display(packet)
        assert rgba.dtype == np.uint8 and rgba.shape == decoded.color.shape
        assert shown_frame.color is None and np.array_equal(shown_frame.depth, decoded.depth)
        c = decoded.color[..., :3]
        srgb = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
        assert np.array_equal(rgba[..., :3], np.rint(255 * srgb).astype(np.uint8))
        assert np.array_equal(rgba[..., 3], (255 * decoded.color[..., 3]).astype(np.uint8))
        # The decoded picture coded again: as display values, the bytes of linear light.
        again = reprise.Frame(decoded.color, frame.depth, frame.motion, camera=frame.camera,
                              fps=frame.fps)
        assert again_display.encode(again, display=rgba) == again_linear.encode(again)
    with pytest.raises(ValueError, match="uint8"):
        again_display.encode(pan_60[0], display=np.zeros((4, 4, 4), np.float32))
    with pytest.raises(ValueError, match="size"):
        again_display.encode(pan_60[0], display=np.zeros((0, 4, 4), np.uint8))
    with pytest.raises(ValueError, match="display=True"):
        linear.decode_display(reprise.Encoder().encode(pan_60[0]))


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
    # Slices: by default one per 24 macroblock rows (one at 160x96); each more restarts the models.
    one = reprise.encode_stream(pan_60[:2], qp=30)
    assert reprise.encode_stream(pan_60[:2], qp=30, slices=1) == one
    three = reprise.encode_stream(pan_60[:2], qp=30, slices=3)
    assert len(three) > len(one)  # each slice: its length, its flush, its models from 1/2
    assert len(reprise.decode_stream(three)) == 2
    for slices in (-1, 65):
        with pytest.raises(ValueError, match="slices"):
            reprise.Encoder(slices=slices)
    # Above qp 34 the view and motion bounds follow the quantiser unless told not to.
    coarse = reprise.encode_stream(pan_60[:3], qp=46)
    fixed = reprise.encode_stream(pan_60[:3], qp=46, bounds_follow_qp=False)
    assert len(coarse) < len(fixed)


def test_anti_aliasing_changes_color_only(renderer):
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


def _packet_offsets(stream):
    """Where each packet of a .rps file starts: a 24-byte file header, then packets of magic,
    version, type, five varints (the last the payload length), the payload and a 4-byte CRC."""
    offsets, at = [], 24
    while at + 6 < len(stream):
        offsets.append(at)
        pos, value = at + 6, 0
        for _ in range(5):
            value, shift = 0, 0
            while True:
                byte = stream[pos]
                pos += 1
                value |= (byte & 0x7F) << shift
                shift += 7
                if byte < 0x80:
                    break
        at = pos + value + 4
    return offsets


def test_decode_stream_recovers_from_damage(pan_60):
    stream = reprise.encode_stream(pan_60, qp=30, keyint=2)  # key frames 0, 2, 4
    intact = reprise.decode_stream(stream)
    frames, errors = reprise.decode_stream(stream, errors="return")
    assert len(frames) == 5 and errors == []
    at = _packet_offsets(stream)
    assert len(at) == 5

    def same(decoded, numbers):
        assert len(decoded) == len(numbers)
        for frame, n in zip(decoded, numbers):
            assert np.array_equal(frame.color, intact[n].color)
            assert np.array_equal(frame.depth, intact[n].depth)

    # One flipped bit in the last packet: the first four frames survive.
    damaged = bytearray(stream)
    damaged[-5] ^= 0x01
    frames, errors = reprise.decode_stream(damaged, errors="return")
    same(frames, [0, 1, 2, 3])
    assert errors == [
        {"kind": "bytes", "offset": at[4], "length": len(stream) - at[4],
         "reason": "packet 4: CRC mismatch"},
        {"kind": "frames", "first": 4, "last": None, "reason": "in the damaged bytes"}]
    # errors="raise" (the default) raises, and the exception carries the frames and the errors.
    with pytest.raises(reprise.Error, match="frames not decoded: after 3") as raised:
        reprise.decode_stream(damaged)
    same(raised.value.frames, [0, 1, 2, 3])
    assert raised.value.errors == errors

    # Frame 1's packet damaged, garbage before frame 3, the tail torn inside frame 4.
    damaged = bytearray(stream[:at[4] + 40])
    damaged[at[1] + 33] ^= 0x80
    damaged[at[3]:at[3]] = b"RPKT" + bytes(range(60))
    frames, errors = reprise.decode_stream(bytes(damaged), errors="return")
    same(frames, [0, 2, 3])
    assert [(e["kind"], e.get("offset"), e.get("length")) for e in errors if e["kind"] == "bytes"] \
        == [("bytes", at[1], at[2] - at[1]), ("bytes", at[3], 64), ("bytes", at[4] + 64, 40)]
    assert [(e["first"], e["last"], e["reason"]) for e in errors if e["kind"] == "frames"] == [
        (1, 1, "in the damaged bytes"), (4, None, "in the damaged bytes")]

    with pytest.raises(ValueError, match="errors"):
        reprise.decode_stream(stream, errors="ignore")
    with pytest.raises(reprise.Error, match="not a reprise stream"):
        reprise.decode_stream(b"XXXX" + stream[4:], errors="return")


def test_motion_within_its_bound(renderer):
    frames = renderer.render_sequence(reprise.Scene("crossing"), frames=3, fps=30.0, **SIZE)
    for bound, tolerance in ((0.25, 0.25), (0.0, np.hypot(1 / 16, 1 / 16))):
        encoder, decoder = reprise.Encoder(motion_error_px=bound), reprise.Decoder()
        for frame in frames:
            decoded = decoder.decode(encoder.encode(frame))
            assert np.array_equal(decoded.motion, encoder.reconstruction.motion)
            finite = np.isfinite(frame.motion).all(axis=-1)
            error = np.linalg.norm(decoded.motion - frame.motion, axis=-1)[finite]
            assert error.max() <= tolerance + 1e-4
        # The cars move on their own: with models each gets a rigid motion (none per pixel).
        assert (encoder.stats["motion_objects"] >= 2) == (bound > 0), encoder.stats
    with pytest.raises(ValueError):
        reprise.Encoder(motion_error_px=0.05)
