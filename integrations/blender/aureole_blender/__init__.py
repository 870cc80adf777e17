"""aureole in Blender: the scene camera's diffraction, bloom and halation
added to what Cycles or Eevee rendered, in the render properties.

A Blender 4.2+ extension (blender_manifest.toml, the aureole wheel bundled)
and a legacy add-on for Blender 3.x (bl_info; the aureole package beside it
in vendor/, or installed in Blender's Python). integrations/blender/README.md
says how to install and use it."""

bl_info = {
    "name": "aureole: camera glare",
    "author": "the aureole developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Render > aureole",
    "description": "Physically based bloom, diffraction rays and halation from the scene camera",
    "doc_url": "https://github.com/aureole-optics/aureole/blob/main/integrations/blender/README.md",
    "category": "Render",
}

import pathlib
import sys
import tomllib

import bpy
from bpy.app.handlers import persistent
from bpy.props import BoolProperty, EnumProperty, FloatProperty, PointerProperty, StringProperty

from . import jobs, lens


def _import_aureole():
    """The aureole package: installed in Blender's Python (an extension's
    wheel), else the copy a legacy add-on carries in vendor/."""
    try:
        import aureole
        return aureole
    except ImportError:
        vendor = pathlib.Path(__file__).parent / "vendor"
        if vendor.is_dir() and str(vendor) not in sys.path:
            sys.path.insert(0, str(vendor))
        try:
            import aureole
            return aureole
        except ImportError:
            return None


aureole = _import_aureole()
RUNNER = jobs.Runner()
_MISSING = ("the aureole Python package is missing: install the extension with its wheel, "
            "or put the package in the add-on's vendor folder")


def _effect_items():
    items = [("NONE", "None", "Only the stop of the scene camera"),
             ("TOML", "TOML file", "An aureole config file: its effects follow the stop")]
    if aureole is not None:
        items += [(name, name, about) for name, about in aureole.presets()]
    return items


def _ghost_items():
    items = [("NONE", "None", "No lens ghosts")]
    if aureole is not None:
        items += [(name, name, about) for name, about in aureole.lenses()]
    return items


# Blender keeps the strings of enum items only while Python references them.
EFFECT_ITEMS = _effect_items()
GHOST_ITEMS = _ghost_items()


class AureoleSettings(bpy.types.PropertyGroup):
    after_render: BoolProperty(
        name="Apply after rendering",
        description="Apply the camera after every render: each frame an animation writes "
                    "(OpenEXR only), or a still's Render Result; the results in the output folder",
        default=False)
    stop_from_camera: BoolProperty(
        name="Stop from the scene camera",
        description="Diffraction of the active camera's stop: its blades, f-stop and rotation, "
                    "the focal length, and the sensor width over the render's width in pixels",
        default=True)
    effects: EnumProperty(
        name="Effects", items=EFFECT_ITEMS,
        description="More of a camera: a preset or a TOML file (bloom, film halation, dirt, "
                    "glare), after the stop; the scene camera's sensor, lens and f-stop replace "
                    "theirs")
    ghosts: EnumProperty(
        name="Lens ghosts", items=GHOST_ITEMS,
        description="The ghosts a real lens throws of the brightest lamps: every path of two "
                    "reflections through a shipped lens's prescription, at the scene camera's "
                    "focal length and f-stop, shaped by its blades")
    config: StringProperty(name="TOML", subtype="FILE_PATH",
                           description="An aureole config file (aureole presets NAME > my.toml)")
    threshold: FloatProperty(
        name="Threshold", min=0.0, soft_max=1e6, default=0.0, precision=1,
        description="cd/m²: pixels at or below it keep their light in place; 0 spreads all")
    scale: FloatProperty(
        name="cd/m² per unit", min=1e-9, soft_max=1e6, default=lens.BLENDER_UNIT_CD_M2,
        description="The luminance of one unit of Blender's scene-linear radiance. 683: an "
                    "emission of strength 1 is 1 W/(m²·sr) at 683 lm/W, the factor Blender's "
                    "glTF exporter converts its lights with. Cycles' film exposure is taken "
                    "into account")
    layers: BoolProperty(
        name="Glare in layers",
        description="Also write the light each effect adds as a layer of its own "
                    "(glare.aperture, glare.bloom, …) beside the passes")
    device: EnumProperty(
        name="Device", default="AUTO",
        items=[("AUTO", "Auto", "A hardware GPU when there is one, else the CPU"),
               ("CPU", "CPU", "The CPU"),
               ("GPU", "GPU", "A GPU (Vulkan, Metal, DX12), a software one too")])
    output_dir: StringProperty(
        name="Output folder", subtype="DIR_PATH", default="",
        description="Where the results go, each named as its frame; empty: a folder "
                    "'aureole' beside the frames")


def settings(scene):
    return scene.aureole


def lens_of(scene):
    """The active camera and the render's size, as lens.Lens."""
    camera = scene.camera
    if camera is None or camera.type != "CAMERA":
        raise lens.LensError("the scene has no active camera")
    data, render = camera.data, scene.render
    scale = render.resolution_percentage / 100.0
    width = int(render.resolution_x * scale)
    height = int(render.resolution_y * scale)
    sensor_width, sensor_height = data.sensor_width, data.sensor_height
    if render.use_border and render.use_crop_to_border:
        # A cropped render is a window of the sensor.
        span_x = render.border_max_x - render.border_min_x
        span_y = render.border_max_y - render.border_min_y
        width, height = round(width * span_x), round(height * span_y)
        sensor_width *= span_x
        sensor_height *= span_y
    return lens.Lens(
        blades=data.dof.aperture_blades,
        f_number=data.dof.aperture_fstop,
        rotation_rad=data.dof.aperture_rotation,
        ratio=data.dof.aperture_ratio,
        focal_length_mm=data.lens,
        sensor_width_mm=sensor_width,
        sensor_height_mm=sensor_height,
        sensor_fit=data.sensor_fit,
        width_px=width,
        height_px=height,
        pixel_aspect=render.pixel_aspect_x / render.pixel_aspect_y,
        kind=data.type,
    )


def _has_stop(camera):
    effects = tomllib.loads(camera.toml()).get("effect", [])
    return any(effect.get("type") == "aperture" for effect in effects)


def build_camera(scene):
    """The aureole camera of the panel's settings, and what to say about it."""
    if aureole is None:
        raise lens.LensError(_MISSING)
    s = settings(scene)
    parts, notes = [], []
    if s.effects == "TOML":
        if not s.config:
            raise lens.LensError("Effects is TOML file, but no file is chosen")
        parts.append(aureole.Camera.from_file(bpy.path.abspath(s.config)))
    elif s.effects != "NONE":
        parts.append(aureole.Camera.preset(s.effects))
    if s.stop_from_camera:
        if any(_has_stop(part) for part in parts):
            raise lens.LensError(
                "the chosen effects have a stop of their own: turn off 'Stop from the scene "
                "camera', or choose effects without an aperture")
        scene_lens = lens_of(scene)
        parts.append(aureole.Camera.from_toml(scene_lens.toml(), "the scene camera"))
        notes += scene_lens.notes()
    if s.ghosts != "NONE":
        parts.append(aureole.Camera.from_toml(lens.ghosts_toml(s.ghosts), "the lens ghosts"))
    if not parts:
        raise lens.LensError(
            "nothing to add: choose the stop from the scene camera, effects or lens ghosts")
    return aureole.Camera.compose(*parts), notes


# The camera last applied, by its TOML: the frames of an animation apply
# the same object, whose sessions keep the kernel built for the first.
_LAST = {"toml": None, "camera": None}


def camera_for(scene):
    """build_camera's camera, the one applied before where it is the same."""
    camera, notes = build_camera(scene)
    text = camera.toml()
    if _LAST["toml"] != text:
        _LAST.update(toml=text, camera=camera)
    return _LAST["camera"], notes


def input_scale(scene):
    """cd/m² per unit of the frames Blender writes: Cycles' film exposure
    multiplies what it renders."""
    exposure = 1.0
    if scene.render.engine == "CYCLES" and hasattr(scene, "cycles"):
        exposure = scene.cycles.film_exposure
    return settings(scene).scale / exposure


def apply_options(scene):
    s = settings(scene)
    return {"threshold": s.threshold, "input_scale": input_scale(scene),
            "layers": s.layers, "device": s.device.lower()}


def output_for(scene, source):
    folder = settings(scene).output_dir
    base = pathlib.Path(bpy.path.abspath(folder)) if folder else source.parent / "aureole"
    return base / source.name


def submit(scene, source):
    """A job for the frame at `source`; in the background (blender -b, a
    farm) it runs at once, so that Blender does not quit before it ends."""
    camera, notes = camera_for(scene)
    job = jobs.Job(source=source, output=output_for(scene, source), camera=camera,
                   options=apply_options(scene))
    for note in notes:
        print(f"aureole: note: {note}")
    if bpy.app.background:
        job.run()
        job.reported = True
        RUNNER.jobs.append(job)
        RUNNER.trim(keep=8)
        _say(job)
    else:
        RUNNER.submit(job)
        _watch()
    return job


def _say(job):
    if job.state == "done":
        r = job.result
        print(f"aureole: wrote {job.output}: energy in {r['energy_in']:.6e} out "
              f"{r['energy_out']:.6e}, {r['spread_pixels']} px spread")
    else:
        print(f"aureole: {job.source}: {job.state}: {job.message}", file=sys.stderr)


def apply_render_result(scene):
    """The Render Result (a still render, F12) written as Blender writes a
    multilayer float EXR, every pass scene-linear, and submitted."""
    result = bpy.data.images.get("Render Result")
    nothing = lens.LensError("no render to apply to: render a frame first (F12)")
    if result is None:
        raise nothing
    source = pathlib.Path(bpy.app.tempdir or ".") / f"render.{scene.frame_current:04d}.exr"
    image_settings = scene.render.image_settings
    kept = (image_settings.file_format, image_settings.color_depth)
    try:
        image_settings.file_format = "OPEN_EXR_MULTILAYER"
        image_settings.color_depth = "32"
        result.save_render(str(source), scene=scene)
    except RuntimeError:
        raise nothing from None
    finally:
        image_settings.file_format, image_settings.color_depth = kept
    return submit(scene, source)


EXR_FORMATS = {"OPEN_EXR", "OPEN_EXR_MULTILAYER"}
# Whether the render under way wrote a frame: one that did not was a still.
_RENDER = {"wrote": False}


@persistent
def _render_started(scene, *_):
    _RENDER["wrote"] = False


@persistent
def _render_ended(scene, *_):
    if _RENDER["wrote"] or not settings(scene).after_render:
        return

    def still():
        try:
            apply_render_result(scene)
        except (lens.LensError, ValueError, OSError) as error:
            print(f"aureole: not applied: {error}", file=sys.stderr)

    if bpy.app.background:
        still()
    else:
        # An interactive render ends on the render's own thread: the Render
        # Result is saved from the main thread, by a timer.
        bpy.app.timers.register(still, first_interval=0.0)


@persistent
def _after_write(scene, *_):
    _RENDER["wrote"] = True
    s = settings(scene)
    if not s.after_render:
        return
    if scene.render.image_settings.file_format not in EXR_FORMATS:
        print("aureole: not applied: the render writes "
              f"{scene.render.image_settings.file_format}, a picture for a display; "
              "write OpenEXR (scene-linear) for aureole", file=sys.stderr)
        return
    source = pathlib.Path(bpy.path.abspath(scene.render.frame_path(frame=scene.frame_current)))
    try:
        submit(scene, source)
    except (lens.LensError, ValueError, OSError) as error:
        print(f"aureole: not applied: {error}", file=sys.stderr)


def _show(path):
    """The result in Blender's image editors."""
    image = bpy.data.images.load(str(path), check_existing=True)
    image.reload()
    for window in bpy.context.window_manager.windows:
        for area in window.screen.areas:
            if area.type == "IMAGE_EDITOR":
                area.spaces.active.image = image
    return image


def _poll():
    """The timer that follows the jobs from Blender's main thread."""
    for job in list(RUNNER.jobs):
        if job.finished and not job.reported:
            job.reported = True
            _say(job)
            if job.state == "done":
                _show(job.output)
    RUNNER.trim(keep=8)
    for window in bpy.context.window_manager.windows:
        for area in window.screen.areas:
            if area.type == "PROPERTIES":
                area.tag_redraw()
    return 0.25 if RUNNER.busy() else None


def _watch():
    if not bpy.app.timers.is_registered(_poll):
        bpy.app.timers.register(_poll, first_interval=0.1)


class AUREOLE_OT_apply_render(bpy.types.Operator):
    """Apply the camera to the Render Result (a still render) and show it"""

    bl_idname = "aureole.apply_render"
    bl_label = "Apply to Render Result"

    def execute(self, context):
        try:
            apply_render_result(context.scene)
        except (lens.LensError, ValueError, OSError) as error:
            self.report({"ERROR"}, f"aureole: {error}")
            return {"CANCELLED"}
        return {"FINISHED"}


class AUREOLE_OT_apply_frames(bpy.types.Operator):
    """Apply the camera to the frames of the scene's range that the render
    output already holds"""

    bl_idname = "aureole.apply_frames"
    bl_label = "Apply to Written Frames"

    def execute(self, context):
        scene = context.scene
        found = 0
        for frame in range(scene.frame_start, scene.frame_end + 1, scene.frame_step):
            source = pathlib.Path(bpy.path.abspath(scene.render.frame_path(frame=frame)))
            if not source.is_file():
                continue
            try:
                submit(scene, source)
            except (lens.LensError, ValueError, OSError) as error:
                self.report({"ERROR"}, f"aureole: {error}")
                return {"CANCELLED"}
            found += 1
        if not found:
            self.report({"WARNING"}, "aureole: the render output holds none of the scene's frames")
            return {"CANCELLED"}
        self.report({"INFO"}, f"aureole: {found} frame{'s' if found > 1 else ''} applied"
                    if bpy.app.background else
                    f"aureole: {found} frame{'s' if found > 1 else ''} queued")
        return {"FINISHED"}


class AUREOLE_OT_cancel(bpy.types.Operator):
    """Stop the frame being applied and drop those waiting"""

    bl_idname = "aureole.cancel"
    bl_label = "Cancel"

    def execute(self, context):
        RUNNER.cancel_all()
        return {"FINISHED"}


class AUREOLE_PT_panel(bpy.types.Panel):
    bl_label = "aureole: camera glare"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        scene = context.scene
        s = settings(scene)
        if aureole is None:
            layout.label(text=_MISSING, icon="ERROR")
            return
        layout.prop(s, "after_render")
        column = layout.column()
        column.prop(s, "stop_from_camera")
        if s.stop_from_camera:
            try:
                scene_lens = lens_of(scene)
                scene_lens.check()
                pitch = scene_lens.sensor_span_mm() * 1000.0 / max(scene_lens.width_px, 1)
                stop = f"{scene_lens.blades} blades" if scene_lens.blades else "a round stop"
                column.label(text=f"{stop}, f/{scene_lens.f_number:g}, "
                                  f"{scene_lens.focal_length_mm:g} mm, pixels of {pitch:.2f} µm",
                             icon="CAMERA_DATA")
                for note in scene_lens.notes():
                    column.label(text=note, icon="INFO")
            except lens.LensError as error:
                column.label(text=str(error), icon="ERROR")
        layout.prop(s, "effects")
        if s.effects == "TOML":
            layout.prop(s, "config")
        layout.prop(s, "ghosts")
        layout.prop(s, "threshold")
        layout.prop(s, "scale")
        layout.prop(s, "layers")
        layout.prop(s, "device")
        layout.prop(s, "output_dir")
        row = layout.row()
        row.operator(AUREOLE_OT_apply_render.bl_idname, icon="RENDER_RESULT")
        row.operator(AUREOLE_OT_apply_frames.bl_idname, icon="RENDER_ANIMATION")
        if RUNNER.busy():
            layout.operator(AUREOLE_OT_cancel.bl_idname, icon="CANCEL")
        for job in RUNNER.jobs[-4:]:
            name = job.source.name
            if job.state == "running":
                layout.label(text=f"{name}: {job.stage} {job.fraction:.0%}", icon="TIME")
            elif job.state == "failed":
                layout.label(text=f"{name}: {job.message}", icon="ERROR")
            else:
                layout.label(text=f"{name}: {job.state}")


CLASSES = (AureoleSettings, AUREOLE_OT_apply_render, AUREOLE_OT_apply_frames,
           AUREOLE_OT_cancel, AUREOLE_PT_panel)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.aureole = PointerProperty(type=AureoleSettings)
    bpy.app.handlers.render_init.append(_render_started)
    bpy.app.handlers.render_write.append(_after_write)
    bpy.app.handlers.render_complete.append(_render_ended)


def unregister():
    RUNNER.cancel_all()
    for handlers, handler in ((bpy.app.handlers.render_init, _render_started),
                              (bpy.app.handlers.render_write, _after_write),
                              (bpy.app.handlers.render_complete, _render_ended)):
        if handler in handlers:
            handlers.remove(handler)
    if bpy.app.timers.is_registered(_poll):
        bpy.app.timers.unregister(_poll)
    del bpy.types.Scene.aureole
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
