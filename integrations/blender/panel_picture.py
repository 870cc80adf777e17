"""Run inside Blender with a window (pictures.py starts it under Xvfb):
installs the add-on, gives the scene a 7-blade f/8 camera, opens Render
Properties filtered to the add-on's panel and saves that area as a PNG.

  blender --factory-startup -P panel_picture.py -- ADDON_ZIP OUT.png"""

import pathlib
import sys

import bpy

zip_path, out = (pathlib.Path(a) for a in sys.argv[sys.argv.index("--") + 1:][:2])
bpy.context.preferences.view.show_splash = False
bpy.ops.preferences.addon_install(filepath=str(zip_path), overwrite=True)
bpy.ops.preferences.addon_enable(module="aureole_blender")

scene = bpy.context.scene
scene.render.engine = "CYCLES"
scene.camera.data.dof.aperture_blades = 7
scene.camera.data.dof.aperture_fstop = 8.0
scene.render.resolution_x, scene.render.resolution_y = 1920, 1080


def largest_area():
    window = bpy.context.window_manager.windows[0]
    return window, max(window.screen.areas, key=lambda a: a.width * a.height)


# Each step waits for a redraw: an editor's tabs exist once it is drawn.
def to_properties():
    largest_area()[1].type = "PROPERTIES"
    bpy.app.timers.register(to_render_tab, first_interval=1.0)


def to_render_tab():
    _, area = largest_area()
    space = area.spaces.active
    space.context = "RENDER"
    # The search opens the panel whose name matches and folds the others.
    space.search_filter = "aureole"
    area.tag_redraw()
    bpy.app.timers.register(save, first_interval=1.0)


def save():
    window, area = largest_area()
    with bpy.context.temp_override(window=window, area=area):
        bpy.ops.screen.screenshot_area(filepath=str(out))
    bpy.ops.wm.quit_blender()


bpy.app.timers.register(to_properties, first_interval=2.0)
