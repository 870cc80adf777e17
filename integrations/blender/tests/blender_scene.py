"""Run inside Blender (blender -b --factory-startup --python-exit-code 1 -P
this -- ADDON_ZIP OUT, or with Blender as a Python module: python this --
ADDON_ZIP OUT): installs the add-on from its zip, makes a night
scene (one emissive lamp of known luminance, a camera of 7 blades at f/8),
renders frame 1 with Cycles into OUT/render.0001.exr with the add-on
applying after the render (into OUT/aureole/), renders it as a still
(applied after it, into OUT/after-still/; and from the Render Result, into
OUT/still/), then turns the stop to 6
blades and applies to the written frame again (into OUT/six/). test_blender.py checks the files."""

import math
import pathlib
import sys

import bpy

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from blender_install import install  # noqa: E402 - beside this script

zip_path, out = (pathlib.Path(a) for a in sys.argv[sys.argv.index("--") + 1:][:2])
install(zip_path)

scene = bpy.context.scene
for thing in list(bpy.data.objects):
    bpy.data.objects.remove(thing)

# A black world: the lamp is the only light.
world = bpy.data.worlds.new("night")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
scene.world = world

# The lamp: a sphere 3 cm across whose surface emits 1 W/(m²·sr) × 100,
# 68300 cd/m² at the add-on's 683 cd/m² per unit, centred on a pixel's
# centre 10 m in front of the lens.
PIXEL_M = 0.006 / 0.050 * 10.0 / 128  # sensor / focal length × distance / pixels
bpy.ops.mesh.primitive_uv_sphere_add(radius=0.015, segments=48, ring_count=24,
                                     location=(PIXEL_M / 2, 0.0, PIXEL_M / 2))
lamp = bpy.context.active_object
material = bpy.data.materials.new("lamp")
material.use_nodes = True
nodes = material.node_tree.nodes
nodes.clear()
emission = nodes.new("ShaderNodeEmission")
emission.inputs["Strength"].default_value = 100.0
emission.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
output = nodes.new("ShaderNodeOutputMaterial")
material.node_tree.links.new(emission.outputs["Emission"], output.inputs["Surface"])
lamp.data.materials.append(material)

camera_data = bpy.data.cameras.new("camera")
camera_data.lens = 50.0
camera_data.sensor_fit = "HORIZONTAL"
camera_data.sensor_width = 6.0
camera_data.dof.aperture_blades = 7
camera_data.dof.aperture_fstop = 8.0
camera = bpy.data.objects.new("camera", camera_data)
camera.location = (0.0, -10.0, 0.0)
camera.rotation_euler = (math.pi / 2, 0.0, 0.0)
scene.collection.objects.link(camera)
scene.camera = camera

scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 4
scene.cycles.use_denoising = False
scene.cycles.filter_width = 0.01  # each pixel its own square, no neighbours' light
scene.render.resolution_x, scene.render.resolution_y = 128, 96
scene.render.resolution_percentage = 100
scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
scene.render.image_settings.color_depth = "32"
scene.render.filepath = str(out / "render.####")
scene.frame_start = scene.frame_end = 1
# A pass besides Combined, which the results must keep.
bpy.context.view_layer.use_pass_z = True

settings = scene.aureole
settings.after_render = True
settings.stop_from_camera = True
settings.effects = "NONE"
settings.threshold = 0.0
settings.device = "CPU"
bpy.ops.render.render(animation=True)

# A still render (F12): applied after it by itself, and from the Render
# Result by the panel's button.
settings.output_dir = str(out / "after-still")
bpy.ops.render.render()
settings.after_render = False
settings.output_dir = str(out / "still")
bpy.ops.render.render()
assert bpy.ops.aureole.apply_render() == {"FINISHED"}

camera_data.dof.aperture_blades = 6
settings.output_dir = str(out / "six")
assert bpy.ops.aureole.apply_frames() == {"FINISHED"}

# The lens's ghosts, chosen in the panel, in a layer of their own.
settings.ghosts = "double-gauss-50mm-f1.4"
settings.layers = True
settings.output_dir = str(out / "ghosts")
assert bpy.ops.aureole.apply_frames() == {"FINISHED"}
