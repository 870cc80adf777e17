"""Installs the add-on from its zip in the Blender this runs in, as a user
would: a Blender 4.2+ extension (`…-extension.zip`, its wheel installed by
Blender) or a legacy add-on (`…-legacy.zip`). Returns the add-on's module.
Blender keeps it under the folders BLENDER_USER_RESOURCES (4.2+) and
BLENDER_USER_SCRIPTS (3.x) name, which the tests point at their own."""

import sys

import bpy


def install(zip_path):
    if zip_path.name.endswith("-extension.zip"):
        done = bpy.ops.extensions.package_install_files(
            filepath=str(zip_path), repo="user_default", enable_on_install=True)
        assert done == {"FINISHED"}, done
        addon = sys.modules["bl_ext.user_default.aureole_blender"]
    else:
        bpy.ops.preferences.addon_install(filepath=str(zip_path), overwrite=True)
        bpy.ops.preferences.addon_enable(module="aureole_blender")
        import aureole_blender as addon
    assert addon.aureole is not None, (
        "the add-on found no aureole package: the wheel must suit Blender's Python "
        f"{sys.version_info.major}.{sys.version_info.minor}")
    print(f"aureole: installed {zip_path.name} in Blender {bpy.app.version_string}")
    return addon
