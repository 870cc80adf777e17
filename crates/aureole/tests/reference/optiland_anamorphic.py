"""Prints where optiland (0.6.3), an optical design library nobody here
wrote, lands real rays through the shipped anamorphic lens and through a
toric singlet: crates/aureole/tests/anamorphic.rs traces the same rays
with aureole's tracer and holds them to these within 0.1 µm. optiland's
toroidal surface is Zemax's (the y–z curve turned about an axis parallel
to y), as aureole's is; a cylinder curved across y is a torus of
infinite radius of rotation, one curved across x a torus whose y–z curve
is a line. Each lens is set up from its TOML file (n_d, no dispersion,
no clipping), the image plane at the given distance behind the last
surface, the rays started where aureole's Layout::collimated starts
them, no ray aiming.

    python3 crates/aureole/tests/reference/optiland_anamorphic.py
"""

import math
import pathlib
import tomllib

import numpy as np
from optiland import optic
from optiland.materials import IdealMaterial
from optiland.rays import RealRays

ROOT = pathlib.Path(__file__).resolve().parents[2]
D_LINE_UM = 0.5875618
TORIC = (pathlib.Path(__file__).parent / "toric-singlet.toml").read_text()
CASES = [
    ("anamorphic-rear-1.3x-f1.8", (ROOT / "lenses" / "anamorphic-rear-1.3x-f1.8.toml").read_text(), 40.0),
    ("toric singlet", TORIC, 10.0),
]
FIELDS = [(0.0, 0.0), (4.0, 0.0), (0.0, 3.0), (5.0, -2.5)]
PUPIL = [(0.0, 0.0), (0.0, 0.6), (0.6, 0.0), (-0.4, 0.3)]


def radius(value):
    return math.inf if value in (None, "flat") else float(value)


def system(lens, pupil_z, pupil_diameter):
    s = optic.Optic()
    s.surfaces.add(index=0, thickness=float("inf"))
    surfaces = lens["surface"]
    for i, surface in enumerate(surfaces, start=1):
        kw = {"index": i, "thickness": surface.get("thickness", 0.0)}
        if surface.get("stop"):
            kw["is_stop"] = True
        elif "radius_y" in surface:
            kw.update(surface_type="toroidal", radius_x=radius(surface.get("radius")),
                      radius_y=radius(surface["radius_y"]), tol=1e-13)
        elif radius(surface.get("radius")) != math.inf:
            kw["radius"] = surface["radius"]
        if "n_d" in surface and not surface.get("stop"):
            kw["material"] = IdealMaterial(n=surface["n_d"])
        s.surfaces.add(**kw)
    s.surfaces.add(index=len(surfaces) + 1)
    s.set_aperture(aperture_type="EPD", value=pupil_diameter)
    s.fields.set_type("angle")
    s.fields.add(y=0)
    s.wavelengths.add(value=D_LINE_UM, is_primary=True)
    return s


for name, text, pupil_diameter in CASES:
    lens = tomllib.loads(text)
    widest = max(s["semi_aperture"] for s in lens["surface"])
    # The entrance pupil's plane: aureole's paraxial one, printed by
    # `aureole lens FILE --json` (entrance_pupil); 0 for the singlet,
    # whose stop is in front.
    pupil_z = 82.82618034592751 if name.startswith("anamorphic") else 0.0
    s = system(lens, pupil_z, pupil_diameter)
    for ax, ay in FIELDS:
        tx, ty = math.tan(math.radians(ax)), math.tan(math.radians(ay))
        d = np.array([tx, ty, 1.0]) / math.sqrt(tx * tx + ty * ty + 1.0)
        for px, py in PUPIL:
            at = np.array([px * pupil_diameter / 2, py * pupil_diameter / 2, pupil_z])
            p = at - (pupil_z + widest + 1.0) / d[2] * d
            rays = RealRays(x=p[0:1], y=p[1:2], z=p[2:3], L=d[0:1], M=d[1:2], N=d[2:3],
                            intensity=np.ones(1), wavelength=np.full(1, D_LINE_UM))
            s.surfaces.trace(rays)
            x, y = float(rays.x[0]), float(rays.y[0])
            print(f'("{name}", ({ax}, {ay}), ({px}, {py}), ({x:.10}, {y:.10})),')
