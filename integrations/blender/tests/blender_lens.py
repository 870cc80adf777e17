"""Run inside Blender (blender -b --factory-startup --python-exit-code 1 -P
this -- ADDON_ZIP): the add-on's reading of the camera against Blender's
own frame (Camera.view_frame), for each sensor fit, portrait and
landscape, a resolution percentage and a cropped border; and the cameras
it refuses."""

import math
import pathlib
import sys

import bpy

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from blender_install import install  # noqa: E402 - beside this script

aureole_blender = install(pathlib.Path(sys.argv[sys.argv.index("--") + 1]))
lens = aureole_blender.lens

scene = bpy.context.scene
camera = scene.camera.data
render = scene.render
camera.lens = 35.0
camera.sensor_width, camera.sensor_height = 36.0, 24.0


def blender_span_mm():
    """The sensor width the image's width spans, from Blender's frame: its
    width over its depth is the span over the focal length."""
    frame = camera.view_frame(scene=scene)
    xs = [corner.x for corner in frame]
    width = max(xs) - min(xs)
    if render.use_border and render.use_crop_to_border:
        width *= render.border_max_x - render.border_min_x
    return camera.lens * width / abs(frame[0].z)


checked = 0
for fit in ("AUTO", "HORIZONTAL", "VERTICAL"):
    for size in ((1920, 1080), (1080, 1920), (1000, 1000)):
        for percentage in (100, 50):
            camera.sensor_fit = fit
            render.resolution_x, render.resolution_y = size
            render.resolution_percentage = percentage
            read = aureole_blender.lens_of(scene)
            expected = blender_span_mm()
            assert math.isclose(read.sensor_span_mm(), expected, rel_tol=1e-5), (
                fit, size, percentage, read.sensor_span_mm(), expected)
            assert read.width_px == size[0] * percentage // 100
            checked += 1

render.resolution_x, render.resolution_y, render.resolution_percentage = 1920, 1080, 100
camera.sensor_fit = "HORIZONTAL"
render.use_border = render.use_crop_to_border = True
render.border_min_x, render.border_max_x = 0.25, 0.75
render.border_min_y, render.border_max_y = 0.0, 1.0
read = aureole_blender.lens_of(scene)
assert read.width_px == 960 and math.isclose(read.sensor_span_mm(), 18.0, rel_tol=1e-6), read
# The pitch of a cropped render is the full render's.
assert math.isclose(read.sensor_span_mm() / read.width_px, 36.0 / 1920, rel_tol=1e-6)
render.use_border = False

camera.type = "ORTHO"
try:
    aureole_blender.lens_of(scene).toml()
    raise AssertionError("an orthographic camera was taken")
except lens.LensError as error:
    assert "orthographic" in str(error), error
camera.type = "PERSP"
render.pixel_aspect_x = 2.0
try:
    aureole_blender.lens_of(scene).toml()
    raise AssertionError("non-square pixels were taken")
except lens.LensError as error:
    assert "pixel aspect 2" in str(error), error
render.pixel_aspect_x = 1.0
camera.dof.aperture_ratio = 1.5
assert any("ratio 1.5" in note for note in aureole_blender.lens_of(scene).notes())
# Frames applied with unchanged settings share one camera, and with it the
# kernel its sessions built; a changed stop is another camera.
first, _ = aureole_blender.camera_for(scene)
assert aureole_blender.camera_for(scene)[0] is first
camera.dof.aperture_blades = 9
assert aureole_blender.camera_for(scene)[0] is not first
print(f"aureole lens: {checked} sensor fits agree with Blender's frame")
