"""Frames as numpy views, EXR frames and sequences in both layouts, and bad input."""
import numpy as np
import pytest

import reprise


def test_channels_are_views_of_the_frame(small_frame):
    color = small_frame.color
    assert color.shape == (6, 8, 4) and color.dtype == np.float32
    assert not color.flags.owndata
    color[2, 3] = (0.25, 0.5, 0.75, 1.0)
    assert np.array_equal(small_frame.color[2, 3], [0.25, 0.5, 0.75, 1.0])
    assert np.shares_memory(small_frame.color, small_frame.color)
    del small_frame  # the view keeps the frame alive
    assert color[2, 3, 1] == 0.5


def test_assignment_copies_into_the_same_buffer(small_frame):
    view = small_frame.depth
    small_frame.depth = np.full((6, 8), 3.0)
    assert np.all(view == 3.0)


def test_rgb_color_gets_alpha_one():
    frame = reprise.Frame(np.zeros((2, 3, 3), np.float64))
    assert frame.color.shape == (2, 3, 4) and np.all(frame.color[..., 3] == 1.0)
    assert frame.depth is None and frame.motion is None


def test_round_trip_reprise_layout(tmp_path, small_frame):
    small_frame.camera = reprise.Camera(view=np.diag([1.0, 1.0, 1.0, 1.0]), near=0.5, far=50.0,
                                        time=1.25, cut=True)
    path = str(tmp_path / "a.exr")
    reprise.write_frame(path, small_frame)
    back = reprise.read_frame(path)
    for name in ("color", "depth", "motion", "normal", "id"):
        assert np.array_equal(getattr(back, name), getattr(small_frame, name)), name
    assert back.camera.near == 0.5 and back.camera.time == 1.25 and back.fps == 24.0
    assert back.camera.cut is True and reprise.Camera().cut is None
    header = reprise.read_header(path)
    assert "motion.x" in header["channels"] and not header["blender"]


def test_round_trip_blender_layout(tmp_path, small_frame):
    path = str(tmp_path / "b.exr")
    reprise.write_frame(path, small_frame, layout="blender")
    header = reprise.read_header(path)
    assert header["blender"]
    for name in ("ViewLayer.Combined.R", "ViewLayer.Depth.Z", "ViewLayer.Vector.W",
                 "ViewLayer.Normal.Z", "ViewLayer.IndexOB.X"):
        assert name in header["channels"]
    assert not any(c in header["channels"] for c in ("R", "Z", "motion.x", "N.X", "id"))
    back = reprise.read_frame(path)
    for name in ("color", "depth", "motion", "normal", "id"):
        assert np.array_equal(getattr(back, name), getattr(small_frame, name)), name


def test_sequences(tmp_path, small_frame):
    other = small_frame.copy()
    other.color = np.zeros((6, 8, 4))
    paths = reprise.write_sequence(str(tmp_path / "seq"), [small_frame, other])
    assert paths[1].endswith("frame_00001.exr")
    files, fps = reprise.open_sequence(str(tmp_path / "seq"))
    assert files == paths and fps == 24.0
    frames = reprise.read_sequence(str(tmp_path / "seq"), start=1)
    assert len(frames) == 1 and np.all(frames[0].color == 0)


@pytest.mark.parametrize("kwargs, error", [
    (dict(color=np.zeros((4, 4, 4), np.int32)), TypeError),
    (dict(color=np.zeros((4, 4))), ValueError),
    (dict(color=np.zeros((4, 4, 5))), ValueError),
    (dict(color=np.zeros((0, 4, 4))), ValueError),
    (dict(color=np.full((4, 4, 4), np.nan)), ValueError),
    (dict(color=np.zeros((4, 4, 4)), depth=np.full((4, 4), np.nan)), ValueError),
    (dict(color=np.zeros((4, 4, 4)), depth=np.full((4, 4), -1.0)), ValueError),
    (dict(color=np.zeros((4, 4, 4)), depth=np.ones((4, 5))), ValueError),
    (dict(color=np.zeros((4, 4, 4)), motion=np.full((4, 4, 2), np.inf)), ValueError),
    (dict(color=np.zeros((4, 4, 4)), id=np.full((4, 4), -1)), ValueError),
    (dict(color=np.zeros((4, 4, 4)), id=np.zeros((4, 4), np.float32)), TypeError),
    (dict(color="not an image"), TypeError),
    (dict(color=np.zeros((4, 4, 4)), fps=-1.0), ValueError),
])
def test_bad_frames_raise(kwargs, error):
    with pytest.raises(error):
        reprise.Frame(**kwargs)


def test_bad_channel_assignment_raises(small_frame):
    with pytest.raises(ValueError, match="depth"):
        small_frame.depth = np.ones((3, 3))
    with pytest.raises(ValueError, match="cannot be dropped"):
        small_frame.motion = None
    with pytest.raises(ValueError, match="4x4"):
        small_frame.camera.view = np.eye(3)
    with pytest.raises(ValueError):
        reprise.Camera(view=np.full((4, 4), np.nan))


def test_file_errors_carry_the_library_message(tmp_path):
    with pytest.raises(reprise.Error, match="missing.exr"):
        reprise.read_frame(str(tmp_path / "missing.exr"))
    garbage = tmp_path / "garbage.exr"
    garbage.write_bytes(b"v/1\x01" + bytes(200))
    with pytest.raises(reprise.Error, match="garbage.exr"):
        reprise.read_frame(str(garbage))
    with pytest.raises(ValueError, match="layout"):
        reprise.write_frame(str(tmp_path / "x.exr"), reprise.Frame(np.zeros((2, 2, 4))), "nuke")
    with pytest.raises(reprise.Error):
        reprise.write_frame(str(tmp_path / "no" / "such" / "dir.exr"),
                            reprise.Frame(np.zeros((2, 2, 4))))


@pytest.mark.parametrize("layout", ["reprise", "blender"])
def test_ui_layer_round_trip(tmp_path, small_frame, layout):
    assert small_frame.ui is None
    ui = np.zeros((6, 8, 4), np.float32)
    ui[1:3, 2:5] = (0.2, 0.1, 0.0, 0.5)  # premultiplied
    small_frame.ui = ui
    assert "ui" in repr(small_frame)
    path = str(tmp_path / "ui.exr")
    reprise.write_frame(path, small_frame, layout=layout)
    header = reprise.read_header(path)
    assert ("ui.A" if layout == "reprise" else "ViewLayer.UI.A") in header["channels"]
    back = reprise.read_frame(path)
    assert np.array_equal(back.ui, ui)
    assert np.array_equal(back.color, small_frame.color)
