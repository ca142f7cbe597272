"""The second eye from one rendered eye, against the rendered second eye."""
import numpy as np
import pytest

import reprise
from conftest import SIZE, psnr


def test_synthesized_eye_is_close_to_the_rendered_one(renderer, pan_60):
    left = pan_60[2]
    left_camera, right_camera = reprise.eye_cameras(left.camera, ipd=0.2, anchor="left")
    assert np.array_equal(left_camera.view, left.camera.view)
    assert right_camera.view[0, 3] != left_camera.view[0, 3]
    scene = reprise.Scene("pan")
    truth = renderer.render_camera(scene, right_camera, time=left.camera.time,
                                   prev_time=left.camera.time - 1 / 60, **SIZE)
    made, stats = reprise.StereoSynthesizer().synthesize(left, right_camera)
    assert stats["covered"] > 0.9 * left.width * left.height
    same = reprise.synthesize_eye(left, ipd=0.2, rendered_eye="left")
    assert np.array_equal(same.color, made.color)
    print(f"synthesized right eye {psnr(truth, made):.2f} dB, left eye as is "
          f"{psnr(truth, left):.2f} dB")
    assert psnr(truth, made) > psnr(truth, left) + 3.0
    assert psnr(truth, made) > 28.0
    kept, _ = reprise.StereoSynthesizer().synthesize(left, right_camera, widen_silhouettes=False)
    print(f"silhouettes kept: {psnr(truth, kept):.2f} dB")
    assert not np.array_equal(kept.color, made.color)
    bicubic, _ = reprise.StereoSynthesizer().synthesize(left, right_camera, warp="grid-bicubic")
    assert np.array_equal(bicubic.color, made.color)  # the grid's default fetch
    bilinear, _ = reprise.StereoSynthesizer().synthesize(left, right_camera, warp="grid-bilinear")
    print(f"bilinear fetch: {psnr(truth, bilinear):.2f} dB")
    assert not np.array_equal(bilinear.color, made.color)
    assert psnr(truth, bilinear) > 28.0
    linear, _ = reprise.StereoSynthesizer().synthesize(left, right_camera, perceptual=False)
    print(f"in linear light: {psnr(truth, linear):.2f} dB")
    assert not np.array_equal(linear.color, made.color)
    assert psnr(truth, linear) > 28.0
    with pytest.raises(ValueError, match="grid-bilinear"):
        reprise.StereoSynthesizer().synthesize(left, right_camera, warp="grid-cubic")


def test_the_gpu_backend_makes_the_cpus_eyes(pan_60):
    left = pan_60[2]
    _, right_camera = reprise.eye_cameras(left.camera, ipd=0.064, anchor="left")
    # The GPU's eye works in linear light: the CPU's is made so to compare them.
    cpu, cpu_stats = reprise.StereoSynthesizer().synthesize(left, right_camera, warp="splat",
                                                            perceptual=False)
    gles = reprise.StereoSynthesizer(backend="gles")
    gpu, gpu_stats = gles.synthesize(left, right_camera, warp="splat")
    # The bar for the GPU backend; on llvmpipe the eyes are bit-identical.
    assert reprise.psnr(reprise.to_display(gpu.color), reprise.to_display(cpu.color)) >= 50.0
    assert gpu_stats["holes"] == cpu_stats["holes"] and gpu_stats["holes"] > 0
    # The default eye, the grid: its cells grown and drawn on the GPU (in linear light).
    cpu_grid, cpu_grid_stats = reprise.StereoSynthesizer().synthesize(left, right_camera,
                                                                      perceptual=False)
    gpu_grid, gpu_grid_stats = gles.synthesize(left, right_camera)
    assert reprise.psnr(reprise.to_display(gpu_grid.color),
                        reprise.to_display(cpu_grid.color)) >= 50.0
    # The bar: the same holes within 0.1 % of the pixels (on llvmpipe: the same).
    allowed = left.color.shape[0] * left.color.shape[1] // 1000
    assert gpu_grid_stats["cells"] == cpu_grid_stats["cells"] > 0
    assert cpu_grid_stats["border"] > 0
    assert abs(gpu_grid_stats["border"] - cpu_grid_stats["border"]) <= allowed
    cpu_grid, cpu_grid_stats = reprise.StereoSynthesizer().synthesize(
        left, right_camera, history=pan_60[3], perceptual=False)
    gpu_grid, gpu_grid_stats = gles.synthesize(left, right_camera, history=pan_60[3])
    assert reprise.psnr(reprise.to_display(gpu_grid.color),
                        reprise.to_display(cpu_grid.color)) >= 50.0
    assert abs(gpu_grid_stats["from_history"] - cpu_grid_stats["from_history"]) <= allowed
    with pytest.raises(ValueError, match="Andreev"):
        gles.synthesize(left, right_camera, fill="andreev")
    # With the previous frame as history, filling the holes first: the CPU's eye too.
    cpu, cpu_stats = reprise.StereoSynthesizer().synthesize(left, right_camera, warp="splat",
                                                            history=pan_60[3], perceptual=False)
    gpu, gpu_stats = gles.synthesize(left, right_camera, warp="splat", history=pan_60[3])
    assert reprise.psnr(reprise.to_display(gpu.color), reprise.to_display(cpu.color)) >= 50.0
    assert gpu_stats["from_history"] == cpu_stats["from_history"] > 0
    with pytest.raises(ValueError, match="expected cpu or gles"):
        reprise.StereoSynthesizer(backend="vulkan")


def test_bad_stereo_input_raises(pan_60):
    no_depth = reprise.Frame(np.zeros((4, 4, 4)))
    with pytest.raises(ValueError, match="depth"):
        reprise.synthesize_eye(no_depth)
    with pytest.raises(ValueError, match="rig"):
        reprise.synthesize_eye(pan_60[0], rig="crossed")
    with pytest.raises(ValueError, match="history"):
        reprise.StereoSynthesizer().synthesize(pan_60[0], pan_60[0].camera, history=no_depth)


def test_eye_alternation_makes_each_eye_in_turn(renderer, pan_60):
    scene = reprise.Scene("pan")
    alternation = reprise.EyeAlternation()
    for i in range(3):
        left = pan_60[i]  # the left eye; the right one rendered beside it
        _, right_camera = reprise.eye_cameras(left.camera, ipd=0.2, anchor="left")
        right = renderer.render_camera(scene, right_camera, time=left.camera.time,
                                       prev_time=left.camera.time - 1 / 60, **SIZE)
        eye = reprise.EyeAlternation.rendered_eye(i)
        assert eye == ("left" if i % 2 == 0 else "right")
        rendered, truth = (left, right) if eye == "left" else (right, left)
        made, stats = alternation.next(rendered, eye, truth.camera)
        print(f"alternation frame {i}: {psnr(truth, made):.2f} dB, "
              f"{stats['from_history']} pixels from history")
        assert np.array_equal(made.camera.view, truth.camera.view)
        assert (stats["from_history"] > 0) == (i > 0)
        assert psnr(truth, made) > 28.0
    with pytest.raises(ValueError, match="eye"):
        alternation.next(pan_60[0], "middle", pan_60[0].camera)
