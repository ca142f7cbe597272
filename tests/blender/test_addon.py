"""Headless test of the Blender add-on (integrations/blender/reprise_fruc):

    blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_addon.py -- REPRISE WORKDIR

A textured cube slides and turns in front of a static camera. Cycles renders it twice: at twice
the frame rate (the truth) and at the input rate with the add-on on, which runs `reprise fruc`
x2 and `reprise export --mp4`. The made in-between frames must beat repeating the previous frame
by MARGIN_DB, and Blender must open a frame that reprise wrote and read the same pixels.
"""
import csv
import json
import os
import shutil
import subprocess
import sys

import addon_utils
import bpy

MARGIN_DB = 5.0
INPUT_FRAMES = 5
SIZE = (128, 72)

reprise, work = sys.argv[sys.argv.index("--") + 1:][:2]
work = os.path.abspath(work)
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                                "integrations", "blender"))


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def check(condition, message):
    if not condition:
        fail(message)
    print("ok: " + message)


# --- The add-on registers.
addon_utils.enable("reprise_fruc", default_set=True, handle_error=lambda e: fail(str(e)))
check(hasattr(bpy.types.Scene, "reprise") and hasattr(bpy.types, "REPRISE_PT_output"),
      "add-on registered (scene settings and output panel)")

# --- The scene: a checkered cube over a plane, seen by the startup camera.
scene = bpy.context.scene
cube = bpy.data.objects["Cube"]
material = bpy.data.materials.new("checker")
material.use_nodes = True
nodes = material.node_tree.nodes
checker = nodes.new("ShaderNodeTexChecker")
checker.inputs["Scale"].default_value = 4.0
checker.inputs["Color1"].default_value = (0.9, 0.3, 0.1, 1.0)
checker.inputs["Color2"].default_value = (0.1, 0.2, 0.8, 1.0)
material.node_tree.links.new(checker.outputs["Color"], nodes["Principled BSDF"].inputs["Base Color"])
cube.data.materials.clear()
cube.data.materials.append(material)
bpy.ops.mesh.primitive_plane_add(size=12, location=(0, 0, -1))

scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 16
scene.cycles.use_denoising = False
scene.render.resolution_x, scene.render.resolution_y = SIZE
scene.render.resolution_percentage = 100
scene.render.fps = 24


def animate(frames_per_input):
    """The same motion over INPUT_FRAMES input frames, with frames_per_input frames each."""
    cube.animation_data_clear()
    last = 1 + (INPUT_FRAMES - 1) * frames_per_input
    for frame, x, angle in ((1, -1.2, 0.0), (last, 1.2, 0.8)):
        cube.location.x = x
        cube.rotation_euler.z = angle
        cube.keyframe_insert("location", index=0, frame=frame)
        cube.keyframe_insert("rotation_euler", index=2, frame=frame)
    for curve in cube.animation_data.action.fcurves:
        for key in curve.keyframe_points:
            key.interpolation = "LINEAR"
    scene.frame_start, scene.frame_end = 1, last


# --- Set up passes with the panel's operator; the truth at twice the rate, add-on off.
bpy.ops.reprise.setup_passes()
check(scene.reprise.enabled and scene.view_layers[0].use_pass_vector and
      scene.render.image_settings.file_format == "OPEN_EXR_MULTILAYER",
      "setup operator enables Depth, Vector, multilayer EXR")
scene.reprise.enabled = False
animate(2)
scene.render.filepath = os.path.join(work, "truth", "")
bpy.ops.render.render(animation=True)
check(not os.path.exists(os.path.join(work, "truth", "reprise")), "disabled add-on leaves renders alone")

# --- The input rate with the add-on on: it runs reprise after the animation render.
settings = scene.reprise
settings.enabled = True
settings.factor, settings.mode, settings.method, settings.fill = 2, "interpolate", "grid", "pullpush"
settings.executable = reprise
settings.output = os.path.join(work, "reprise", "")
animate(1)
scene.render.filepath = os.path.join(work, "input", "")
bpy.ops.render.render(animation=True)
print("add-on result: " + settings.last_result)
check(not settings.last_result.startswith("error"), "add-on ran reprise: " + settings.last_result)
made_dir = os.path.join(work, "reprise", "x2")
made = sorted(f for f in os.listdir(made_dir) if f.endswith(".exr"))
check(len(made) == 2 * INPUT_FRAMES - 1, "%d upconverted frames" % len(made))
mp4 = os.path.join(work, "reprise", "x2.mp4")
check(os.path.isfile(mp4) and os.path.getsize(mp4) > 0, "MP4 written")
with open(os.path.join(work, "reprise", "input", "cameras.json")) as f:
    cameras = json.load(f)["frames"]
check(len(cameras) == INPUT_FRAMES - 1 and all(len(c["view"]) == 16 for c in cameras),
      "cameras.json beside the input holds the cameras of the frames after the first")


def psnr(reference, test):
    table = os.path.join(work, "metrics.csv")
    run = subprocess.run([reprise, "metrics", "--ref", reference, "--test", test, "--csv", table],
                         capture_output=True, text=True)
    if run.returncode != 0:
        fail("reprise metrics: " + run.stderr)
    with open(table) as f:
        return float(next(csv.DictReader(f))["psnr"])


# Output k is the instant of truth frame k + 1; odd outputs are made, even ones rendered.
truth = lambda n: os.path.join(work, "truth", "%04d.exr" % n)
made_db, repeated_db = [], []
for k in range(1, len(made), 2):
    made_db.append(psnr(truth(k + 1), os.path.join(made_dir, made[k])))
    repeated_db.append(psnr(truth(k + 1), truth(k)))
    print("in-between %d: reprise %.2f dB, frame repetition %.2f dB" % (k, made_db[-1], repeated_db[-1]))
mean_made, mean_repeated = sum(made_db) / len(made_db), sum(repeated_db) / len(repeated_db)
check(mean_made > mean_repeated + MARGIN_DB,
      "in-between frames %.2f dB beat repetition %.2f dB by more than %.1f dB"
      % (mean_made, mean_repeated, MARGIN_DB))

# --- Blender opens a frame that reprise wrote: a multilayer image with its passes, same pixels.
frame = os.path.join(made_dir, made[1])
image = bpy.data.images.load(frame)
scene.use_nodes = True
tree = scene.node_tree
for node in list(tree.nodes):
    tree.nodes.remove(node)
source = tree.nodes.new("CompositorNodeImage")
source.image = image
outputs = [o.name for o in source.outputs]
check(image.type == "MULTILAYER" and {"Combined", "Depth", "Vector"} <= set(outputs),
      "Blender reads reprise's frame as multilayer with passes %s" % outputs)
composite = tree.nodes.new("CompositorNodeComposite")
composite.use_alpha = True
tree.links.new(source.outputs["Combined"], composite.inputs["Image"])
settings.enabled = False
scene.render.engine = "BLENDER_WORKBENCH"
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_depth = "32"
scene.render.filepath = os.path.join(work, "blender_read.exr")
bpy.ops.render.render(write_still=True)
read_back = psnr(frame, scene.render.filepath)
check(read_back == float("inf"), "Blender's pixels equal reprise's (PSNR %s)" % read_back)
print("PASS")
