"""reprise frame-rate upconversion for Blender renders.

A panel in Properties > Output enables the Depth and Vector passes and multilayer EXR output;
after an animation render the add-on runs `reprise fruc` on the frames Blender wrote, which
writes the upconverted sequence (EXR frames in Blender's multilayer layout) and an MP4.
"""
import json
import os
import shutil
import subprocess

import bpy
from bpy.app.handlers import persistent
from bpy.props import BoolProperty, EnumProperty, IntProperty, PointerProperty, StringProperty

bl_info = {
    "name": "reprise frame-rate upconversion",
    "author": "reprise",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Output > reprise",
    "description": "Renders fewer frames: reprise makes the in-between frames from depth and "
                   "motion vectors",
    "category": "Render",
}


class RepriseSettings(bpy.types.PropertyGroup):
    enabled: BoolProperty(name="Upconvert after rendering", default=False,
                          description="Run reprise fruc on the frames of each animation render")
    factor: IntProperty(name="Factor", default=2, min=2, max=16,
                        description="Output frames per rendered frame")
    mode: EnumProperty(name="Mode", default="interpolate", items=[
        ("interpolate", "Interpolate", "Frames between each pair of rendered frames"),
        ("extrapolate", "Extrapolate", "Frames beyond each rendered frame (no latency)"),
    ])
    method: EnumProperty(name="Warp", default="grid", items=[
        ("grid", "Adaptive grid", "Adaptive-grid warp"),
        ("reverse", "Reverse", "Motion splatted to the new instant, colour fetched back"),
        ("splat", "Splat", "Forward splat of colour"),
    ])
    fill: EnumProperty(name="Hole fill", default="pullpush", items=[
        ("pullpush", "Pull-push", ""), ("andreev", "Andreev", ""), ("none", "None", "")])
    output: StringProperty(name="Output", subtype="DIR_PATH", default="",
                           description="Folder for the upconverted frames and the MP4; "
                                       "empty: a 'reprise' folder beside the rendered frames")
    write_mp4: BoolProperty(name="Write MP4", default=True)
    executable: StringProperty(name="reprise executable", subtype="FILE_PATH", default="",
                               description="Empty: $REPRISE_BINARY, else 'reprise' on PATH")
    last_result: StringProperty(name="Last result", default="")


def find_executable(settings):
    candidates = [bpy.path.abspath(settings.executable) if settings.executable else "",
                  os.environ.get("REPRISE_BINARY", ""), shutil.which("reprise") or ""]
    for path in candidates:
        if path and os.path.isfile(path) and os.access(path, os.X_OK):
            return path
    return None


def passes_missing(scene):
    """What the scene still lacks for reprise, as short phrases."""
    missing = []
    if scene.render.image_settings.file_format != "OPEN_EXR_MULTILAYER":
        missing.append("multilayer EXR output")
    if not all(layer.use_pass_z for layer in scene.view_layers):
        missing.append("Depth pass")
    if not all(layer.use_pass_vector for layer in scene.view_layers):
        missing.append("Vector pass")
    if scene.render.use_motion_blur:
        missing.append("motion blur off (Cycles writes no Vector pass with it)")
    return missing


def upconvert(scene, frames):
    """Runs reprise fruc (and export) on the rendered frame files; returns a one-line result."""
    settings = scene.reprise
    exe = find_executable(settings)
    if exe is None:
        raise RuntimeError("reprise executable not found (set it in the panel or REPRISE_BINARY)")
    out_root = (bpy.path.abspath(settings.output) if settings.output
                else os.path.join(os.path.dirname(frames[0]), "reprise"))
    input_dir = os.path.join(out_root, "input")
    fruc_dir = os.path.join(out_root, "x%d" % settings.factor)
    for folder in (input_dir, fruc_dir):
        shutil.rmtree(folder, ignore_errors=True)
        os.makedirs(folder)
    # Only this render's frames, whatever else lies in Blender's output folder.
    for path in frames:
        link = os.path.join(input_dir, os.path.basename(path))
        try:
            os.symlink(os.path.abspath(path), link)
        except OSError:
            shutil.copyfile(path, link)
    write_cameras(scene, frames, input_dir)
    fps = scene.render.fps / scene.render.fps_base / max(1, scene.frame_step) * settings.factor
    command = [exe, "fruc", "--in", input_dir, "--out", fruc_dir,
               "--factor", str(settings.factor), "--mode", settings.mode,
               "--warp", settings.method, "--fill", settings.fill, "--layout", "blender"]
    run = subprocess.run(command, capture_output=True, text=True)
    if run.returncode != 0:
        raise RuntimeError("reprise fruc failed: " + (run.stderr or run.stdout).strip())
    result = "%d frames -> %s" % (len(frames), fruc_dir)
    if settings.write_mp4:
        mp4 = os.path.join(out_root, "x%d.mp4" % settings.factor)
        run = subprocess.run([exe, "export", fruc_dir, "--mp4", mp4, "--fps", "%g" % fps],
                             capture_output=True, text=True)
        if run.returncode != 0:
            raise RuntimeError("reprise export failed: " + (run.stderr or run.stdout).strip())
        result += ", " + mp4
    return result


_written = []
_cameras = {}  # frame path -> (view, projection, near, far, time, camera name), column-major


def write_cameras(scene, frames, folder):
    """cameras.json for reprise (Blender's files carry no camera): each frame after the first
    gets its camera and the previous frame's, which the Vector pass spans when every frame is
    rendered (frame step 1), and whether the active camera changed since (a cut: markers bound
    to cameras). Without them reprise warps by the Vector pass alone."""
    if scene.frame_step != 1 or any(path not in _cameras for path in frames):
        return
    entries = []
    for previous, path in zip(frames, frames[1:]):
        view, projection, near, far, time, name = _cameras[path]
        entries.append({"file": os.path.basename(path), "time": time, "view": view,
                        "projection": projection, "prev_view": _cameras[previous][0],
                        "prev_projection": _cameras[previous][1], "near": near, "far": far,
                        "cut": name != _cameras[previous][5]})
    with open(os.path.join(folder, "cameras.json"), "w") as f:
        json.dump({"frames": entries}, f)


def camera_matrices(scene):
    """The scene camera's view and projection now, column-major lists as cameras.json holds
    them, or None."""
    camera = scene.camera
    if camera is None or camera.type != "CAMERA":
        return None
    render = scene.render
    scale = render.resolution_percentage / 100.0
    flat = lambda m: [m[r][c] for c in range(4) for r in range(4)]
    try:
        projection = camera.calc_matrix_camera(
            bpy.context.evaluated_depsgraph_get(), x=int(render.resolution_x * scale),
            y=int(render.resolution_y * scale), scale_x=render.pixel_aspect_x,
            scale_y=render.pixel_aspect_y)
    except (RuntimeError, TypeError):
        return None
    return flat(camera.matrix_world.inverted()), flat(projection)


def record_camera(scene, path):
    matrices = camera_matrices(scene)
    if matrices is None:
        return  # no cameras.json then
    render = scene.render
    time = (scene.frame_current - scene.frame_start) * render.fps_base / render.fps
    _cameras[path] = matrices + (scene.camera.data.clip_start, scene.camera.data.clip_end, time,
                                 scene.camera.name)


@persistent
def on_render_init(scene, *_):
    _written.clear()
    _cameras.clear()


@persistent
def on_render_write(scene, *_):
    if scene.reprise.enabled:
        path = scene.render.frame_path(frame=scene.frame_current)
        _written.append(path)
        record_camera(scene, path)


@persistent
def on_render_complete(scene, *_):
    frames = [path for path in _written if os.path.isfile(path)]
    _written.clear()
    if not scene.reprise.enabled or len(frames) < 2:
        return
    try:
        missing = passes_missing(scene)
        if missing:
            raise RuntimeError("not upconverted, the render needs: " + ", ".join(missing))
        scene.reprise.last_result = upconvert(scene, frames)
    except RuntimeError as error:
        scene.reprise.last_result = "error: %s" % error
    print("[reprise] " + scene.reprise.last_result)


class REPRISE_OT_setup_passes(bpy.types.Operator):
    """Enable the Depth and Vector passes, multilayer EXR output, and reprise after renders"""
    bl_idname = "reprise.setup_passes"
    bl_label = "Set up for reprise"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        scene = context.scene
        for layer in scene.view_layers:
            layer.use_pass_z = True
            layer.use_pass_vector = True
        image = scene.render.image_settings
        image.file_format = "OPEN_EXR_MULTILAYER"
        image.color_depth = "32"
        image.exr_codec = "ZIP"
        scene.render.use_motion_blur = False
        scene.reprise.enabled = True
        return {"FINISHED"}


class REPRISE_PT_output(bpy.types.Panel):
    bl_label = "reprise frame-rate upconversion"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "output"
    bl_options = {"DEFAULT_CLOSED"}

    def draw_header(self, context):
        self.layout.prop(context.scene.reprise, "enabled", text="")

    def draw(self, context):
        scene = context.scene
        settings = scene.reprise
        layout = self.layout
        missing = passes_missing(scene)
        if missing:
            box = layout.box()
            box.label(text="Needs: " + ", ".join(missing), icon="ERROR")
        layout.operator(REPRISE_OT_setup_passes.bl_idname, icon="RENDERLAYERS")
        column = layout.column()
        column.active = settings.enabled
        column.prop(settings, "factor")
        column.prop(settings, "mode")
        column.prop(settings, "method")
        column.prop(settings, "fill")
        column.prop(settings, "output")
        column.prop(settings, "write_mp4")
        column.prop(settings, "executable")
        if find_executable(settings) is None:
            column.label(text="reprise executable not found", icon="ERROR")
        if settings.last_result:
            column.label(text=settings.last_result)


classes = (RepriseSettings, REPRISE_OT_setup_passes, REPRISE_PT_output)
handlers = ((bpy.app.handlers.render_init, on_render_init),
            (bpy.app.handlers.render_write, on_render_write),
            (bpy.app.handlers.render_complete, on_render_complete))


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.reprise = PointerProperty(type=RepriseSettings)
    for handler_list, function in handlers:
        if function not in handler_list:
            handler_list.append(function)


def unregister():
    for handler_list, function in handlers:
        if function in handler_list:
            handler_list.remove(function)
    del bpy.types.Scene.reprise
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
