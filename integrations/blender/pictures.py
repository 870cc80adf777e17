#!/usr/bin/env python3
"""The README's two pictures of the Blender add-on, from the headless test's
scene: docs/gallery/blender-render.png (Cycles' render and the add-on's
result side by side) and docs/gallery/blender-panel.png (the panel, in a
Blender window under Xvfb). Needs Blender, xvfb-run and the aureole wheel;
run with the Python that has the aureole package:

  target/pyvenv/bin/python integrations/blender/pictures.py target/wheels/aureole-….whl"""

import os
import pathlib
import subprocess
import sys
import tempfile

import numpy as np

import aureole

HERE = pathlib.Path(__file__).resolve().parent
GALLERY = HERE.parents[1] / "docs" / "gallery"
# 4 px on the page per rendered pixel; white at 14 cd/m² (EV 3.5), so that
# the rays, 10⁻⁵ of the lamp, show.
ZOOM, EV, UNIT_CD_M2 = 4, 3.5, 683.0


def main():
    wheel = pathlib.Path(sys.argv[1])
    with tempfile.TemporaryDirectory() as folder:
        folder = pathlib.Path(folder)
        subprocess.run([sys.executable, HERE / "package.py", "--wheel", wheel,
                        "--out", folder], check=True)
        addon = next(folder.glob("*-legacy.zip"))
        env = dict(os.environ, BLENDER_USER_SCRIPTS=str(folder / "scripts"))
        subprocess.run(["blender", "-b", "--factory-startup", "--python-exit-code", "1",
                        "-P", HERE / "tests" / "blender_scene.py", "--", addon,
                        folder / "out"], check=True, env=env, stdout=subprocess.DEVNULL)
        before, _ = aureole.read(folder / "out" / "render.0001.exr")
        after, _ = aureole.read(folder / "out" / "aureole" / "render.0001.exr")
        gap = np.zeros((before.shape[0], 2, 3), np.float32)
        pair = np.concatenate([before[..., :3], gap, after[..., :3]], axis=1)
        pair = pair.repeat(ZOOM, axis=0).repeat(ZOOM, axis=1)
        aureole.write(GALLERY / "blender-render.png",
                      np.ascontiguousarray(pair * UNIT_CD_M2), exposure=EV)
        subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24", "blender",
                        "--factory-startup", "-P", HERE / "panel_picture.py", "--", addon,
                        GALLERY / "blender-panel.png"], check=True, env=env,
                       stdout=subprocess.DEVNULL)
    print(f"wrote {GALLERY / 'blender-render.png'} and {GALLERY / 'blender-panel.png'}")


if __name__ == "__main__":
    main()
