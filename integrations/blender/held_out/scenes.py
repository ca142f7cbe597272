"""Held-out scenes for `reprise bench fruc --in`: three animations built here from Blender's
primitives and procedural textures, rendered by Cycles with the Depth and Vector passes as
multilayer EXR. No reprise default was tuned on them.

    blender -b --factory-startup --python-exit-code 1 --python scenes.py -- OUT \
        [--size 320x180] [--frames 6] [--factor 2] [--samples 32] [--scenes tumble,orbit,dolly] \
        [--cameras 1] [--stereo IPD]

Each scene is rendered twice over the same seconds: OUT/blender-<scene>/input/ at 30 Hz (frames
inputs; their Vector pass spans 1/30 s, as in a real 30 Hz render) and OUT/blender-<scene>/truth/
at 30 x factor Hz, the frames an upconversion must make; with --cameras 1 a cameras.json beside
the frames of each (Blender's files carry no camera). With --stereo IPD also
OUT/blender-<scene>/right/ at 30 Hz: the right eye of a parallel rig whose left eye is the input
(a camera IPD metres along the camera's own x axis), for `reprise bench stereo --in OUT`.
scripts/blender-scenes runs this.
"""
import argparse
import json
import math
import os
import sys

import bpy

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from reprise_fruc import camera_matrices  # noqa: E402 (the add-on's, shared)

parser = argparse.ArgumentParser(prog="scenes.py")
parser.add_argument("out")
parser.add_argument("--size", default="320x180")
parser.add_argument("--frames", type=int, default=6, help="input frames at 30 Hz")
parser.add_argument("--factor", type=int, default=2)
parser.add_argument("--samples", type=int, default=32)
parser.add_argument("--scenes", default="tumble,orbit,dolly")
parser.add_argument("--cameras", type=int, default=1, help="1: write cameras.json beside the frames")
parser.add_argument("--stereo", type=float, default=0.0, help="IPD > 0: also render the right eye")
args = parser.parse_args(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
width, height = (int(v) for v in args.size.split("x"))
if args.frames < 2 or args.factor < 1 or width < 1 or height < 1 or not args.stereo >= 0.0:
    sys.exit("scenes.py: need --frames >= 2, --factor >= 1, a positive --size and --stereo >= 0")
DURATION = (args.frames - 1) / 30.0  # seconds the animation lasts
LAST = 0  # the last frame of the render being set up (Blender counts from 1)


def clear(rate):
    global LAST
    LAST = 1 + (args.frames - 1) * rate
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = args.samples
    scene.cycles.use_denoising = False
    scene.cycles.use_animated_seed = False
    scene.render.use_motion_blur = False  # Cycles writes no Vector pass with motion blur
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.render.fps = 30 * rate
    scene.frame_start, scene.frame_end = 1, LAST
    layer = scene.view_layers[0]
    layer.use_pass_z = True
    layer.use_pass_vector = True
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"
    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.35, 0.4, 0.5, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.6
    scene.world = world
    return scene


def material(name, kind, a, b, scale):
    """A diffuse material whose colour is a procedural texture between colours a and b."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    texture = nodes.new({"checker": "ShaderNodeTexChecker", "brick": "ShaderNodeTexBrick",
                         "noise": "ShaderNodeTexNoise", "wave": "ShaderNodeTexWave"}[kind])
    texture.inputs["Scale"].default_value = scale
    bsdf = nodes["Principled BSDF"]
    bsdf.inputs["Roughness"].default_value = 0.8
    if kind in ("checker", "brick"):
        texture.inputs["Color1"].default_value = a + (1.0,)
        texture.inputs["Color2"].default_value = b + (1.0,)
        links.new(texture.outputs["Color"], bsdf.inputs["Base Color"])
    else:
        ramp = nodes.new("ShaderNodeValToRGB")
        ramp.color_ramp.elements[0].color = a + (1.0,)
        ramp.color_ramp.elements[1].color = b + (1.0,)
        links.new(texture.outputs["Fac"], ramp.inputs["Fac"])
        links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
    return mat


def add(primitive, location, mat, **kw):
    getattr(bpy.ops.mesh, "primitive_%s_add" % primitive)(location=location, **kw)
    obj = bpy.context.active_object
    obj.data.materials.append(mat)
    if primitive in ("uv_sphere", "cylinder", "monkey", "torus"):
        bpy.ops.object.shade_smooth()
    return obj


def keys(obj, path, values):
    """Linear keys of obj.<path> at the first and last frame, extrapolated linearly beyond them
    (the first frame's Vector pass looks at the frame before it)."""
    for frame, value in zip((1, LAST), values):
        setattr(obj, path, value)
        obj.keyframe_insert(path, frame=frame)
    for curve in obj.animation_data.action.fcurves:
        curve.extrapolation = "LINEAR"
        for key in curve.keyframe_points:
            key.interpolation = "LINEAR"


def camera(location, look_at, lens=35.0):
    bpy.ops.object.camera_add(location=location)
    cam = bpy.context.active_object
    cam.data.lens = lens
    aim(cam, look_at)
    bpy.context.scene.camera = cam
    return cam


def aim(obj, target):
    direction = [t - l for t, l in zip(target, obj.location)]
    from mathutils import Vector
    obj.rotation_euler = Vector(direction).to_track_quat("-Z", "Y").to_euler()


def lights():
    bpy.ops.object.light_add(type="SUN", location=(4, -3, 8))
    sun = bpy.context.active_object
    sun.data.energy = 3.0
    sun.data.angle = math.radians(8)
    sun.rotation_euler = (math.radians(40), math.radians(10), math.radians(30))


def ground(size=30):
    add("plane", (0, 0, 0), material("ground", "brick", (0.55, 0.5, 0.45), (0.25, 0.2, 0.18), 6.0),
        size=size)


def tumble():
    """A textured monkey head tumbles and slides across a brick floor; the camera pans slowly."""
    lights()
    ground()
    add("cube", (-2.5, 2.5, 1), material("box", "checker", (0.8, 0.7, 0.2), (0.1, 0.3, 0.6), 5.0))
    head = add("monkey", (0, 0, 1.4), material("head", "noise", (0.9, 0.3, 0.1), (0.2, 0.1, 0.05),
                                                  6.0))
    keys(head, "location", [(-1.4, 0.0, 1.4), (1.4, -0.4, 1.6)])
    speed = 8.0 * DURATION  # radians over the animation: 8 rad/s
    keys(head, "rotation_euler", [(0.0, 0.0, 0.0), (speed * 0.6, speed * 0.2, speed)])
    cam = camera((0, -8, 3.2), (0, 0, 1.2))
    keys(cam, "location", [(-0.8, -8, 3.2), (0.8, -8, 3.2)])


def orbit():
    """The camera circles a cluster of textured solids: parallax and disocclusion everywhere."""
    lights()
    ground()
    add("cube", (0, 0, 1), material("tiles", "checker", (0.7, 0.25, 0.2), (0.9, 0.85, 0.8), 3.0))
    add("cylinder", (2.0, 1.0, 1.5), material("wave", "wave", (0.1, 0.5, 0.3), (0.9, 0.9, 0.5),
                                               3.0), radius=0.5, depth=3.0)
    add("uv_sphere", (-1.8, 1.2, 0.9), material("dots", "checker", (0.9, 0.9, 0.9),
                                                   (0.2, 0.2, 0.7), 10.0), radius=0.9)
    add("torus", (0.5, -2.0, 0.4), material("ring", "noise", (0.8, 0.5, 0.1), (0.3, 0.1, 0.4),
                                               8.0))
    pivot = bpy.data.objects.new("pivot", None)
    bpy.context.scene.collection.objects.link(pivot)
    cam = camera((0, -9, 4), (0, 0, 1))
    cam.parent = pivot
    keys(pivot, "rotation_euler", [(0, 0, 0), (0, 0, 1.5 * DURATION)])  # 1.5 rad/s


def dolly():
    """The camera flies forward down an avenue of pillars: motion grows from the centre."""
    lights()
    ground(60)
    for i in range(6):
        for side in (-1, 1):
            add("cylinder", (side * 2.2, 4.0 * i, 1.5),
                material("pillar%d%d" % (i, side), "checker" if (i + side) % 2 else "wave",
                         (0.85, 0.8, 0.7), (0.3, 0.25, 0.5), 6.0), radius=0.45, depth=3.0)
    cam = camera((0, -6, 1.6), (0, 10, 1.4), lens=28.0)
    keys(cam, "location", [(0.0, -6.0, 1.6), (0.3, -6.0 + 12.0 * DURATION, 1.7)])  # 12 m/s


def write_cameras(scene, folder):
    """cameras.json beside the frames: Blender's files carry no camera (docs/exr_format.md)."""
    def at(frame):
        scene.frame_set(frame)
        return camera_matrices(scene)
    frames = []
    for frame in range(1, LAST + 1):
        view, projection = at(frame)
        prev_view, prev_projection = at(frame - 1)
        frames.append({"file": "%04d.exr" % frame, "time": (frame - 1) / scene.render.fps,
                       "view": view, "projection": projection, "prev_view": prev_view,
                       "prev_projection": prev_projection, "near": scene.camera.data.clip_start,
                       "far": scene.camera.data.clip_end})
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "cameras.json"), "w") as f:
        json.dump({"frames": frames}, f)
    scene.frame_set(1)


def right_eye(ipd):
    """A camera `ipd` along the scene camera's own x axis, moving with it, made the scene's."""
    scene = bpy.context.scene
    left = scene.camera
    right = bpy.data.objects.new("right eye", left.data)
    scene.collection.objects.link(right)
    right.parent = left
    right.location = (ipd, 0.0, 0.0)
    scene.camera = right


BUILDERS = {"tumble": tumble, "orbit": orbit, "dolly": dolly}
for name in args.scenes.split(","):
    if name not in BUILDERS:
        sys.exit("scenes.py: unknown scene '%s' (%s)" % (name, ", ".join(BUILDERS)))
    passes = [("input", 1), ("truth", args.factor)] + ([("right", 1)] if args.stereo > 0 else [])
    for folder, rate in passes:
        scene = clear(rate)
        BUILDERS[name]()
        if folder == "right":
            right_eye(args.stereo)
        folder = os.path.join(os.path.abspath(args.out), "blender-" + name, folder)
        scene.render.filepath = os.path.join(folder, "")
        if args.cameras:
            write_cameras(scene, folder)
        print("scenes.py: rendering %s/%s, %d frames at %dx%d" % (name, folder, LAST, width, height),
              flush=True)
        bpy.ops.render.render(animation=True)
print("scenes.py: done")
