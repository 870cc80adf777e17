"""Prints where optiland (0.6.3), an optical design library nobody here
wrote, lands real rays of distant sources through two shipped lenses:
the rays that crates/aureole/tests/ghosts.rs traces with aureole's own
tracer and holds to these within 0.1 µm. Each lens is set up from its
TOML file (n_d, no dispersion), the image plane at its paraxial focus,
the entrance pupil of the given diameter; a ray is a field angle along y
(degrees) and a point of the pupil in units of its radius.

    target/pyvenv/bin/python crates/aureole/tests/reference/optiland_rays.py
"""

import pathlib
import tomllib

from optiland import optic
from optiland.materials import IdealMaterial

ROOT = pathlib.Path(__file__).resolve().parents[4]
D_LINE_UM = 0.5875618
CASES = [("double-gauss-50mm-f1.4", 30.0, 20.0), ("telephoto-300mm-f2.8", 90.0, 3.0)]
PUPIL = [(0.0, 0.0), (0.0, 0.7), (0.0, -0.7), (0.7, 0.0), (0.5, 0.5)]


def system(lens, image_gap, pupil_diameter, max_field):
    s = optic.Optic()
    s.surfaces.add(index=0, thickness=float("inf"))
    surfaces = lens["surface"]
    for i, surface in enumerate(surfaces, start=1):
        last = i == len(surfaces)
        kw = {"index": i, "thickness": image_gap if last else surface.get("thickness", 0.0)}
        if surface.get("stop"):
            kw["is_stop"] = True
        elif surface.get("radius", "flat") != "flat":
            kw["radius"] = surface["radius"]
        if "n_d" in surface and not surface.get("stop"):
            kw["material"] = IdealMaterial(n=surface["n_d"])
        s.surfaces.add(**kw)
    s.surfaces.add(index=len(surfaces) + 1)
    s.set_aperture(aperture_type="EPD", value=pupil_diameter)
    s.fields.set_type("angle")
    s.fields.add(y=0)
    s.fields.add(y=max_field)
    s.wavelengths.add(value=D_LINE_UM, is_primary=True)
    return s


for name, pupil_diameter, max_field in CASES:
    lens = tomllib.loads((ROOT / "configs" / "lenses" / f"{name}.toml").read_text())
    first = system(lens, 0.0, pupil_diameter, max_field)
    back = float(first.paraxial.F2())
    s = system(lens, back, pupil_diameter, max_field)
    for field in (0.0, 0.5, 1.0):
        for px, py in PUPIL:
            s.trace_generic(Hx=0.0, Hy=field, Px=px, Py=py, wavelength=D_LINE_UM)
            x = float(s.surfaces.x[-1][0])
            y = float(s.surfaces.y[-1][0])
            degrees = field * max_field
            print(f'("{name}", {pupil_diameter}, {degrees}, ({px}, {py}), ({x:.9}, {y:.9})),')

# Ghosts: the path unfolded into a sequential system, surface `second` a
# mirror sending the light back through the surfaces before it, surface
# `first` a mirror sending it forwards again; rays started where
# aureole's Layout::collimated starts them (on the line through the
# pupil point, in front of every surface), no ray aiming.
import math  # noqa: E402

import numpy as np  # noqa: E402
from optiland.rays import RealRays  # noqa: E402

GHOSTS = [("double-gauss-50mm-f1.4", 20.0, [(1, 4), (4, 5), (0, 8)], [0.0, 5.0])]
GHOST_PUPIL = [(0.0, 0.0), (0.0, 0.5), (0.4, 0.0), (-0.3, 0.2)]


def ghost_system(lens, first, second, image_gap):
    surfaces = lens["surface"]

    def after(s):
        n = 1.0
        for k in range(s + 1):
            if not surfaces[k].get("stop"):
                n = surfaces[k].get("n_d", 1.0)
        return n

    def before(s):
        return 1.0 if s == 0 else after(s - 1)

    s_ = optic.Optic()
    s_.surfaces.add(index=0, thickness=float("inf"))
    order = ([(s, surfaces[s].get("thickness", 0.0), after(s)) for s in range(second)]
             + [(second, -surfaces[second - 1]["thickness"], "mirror")]
             + [(s, -surfaces[s - 1]["thickness"], before(s)) for s in range(second - 1, first, -1)]
             + [(first, surfaces[first]["thickness"], "mirror")]
             + [(s, surfaces[s].get("thickness", 0.0), after(s)) for s in range(first + 1, len(surfaces))])
    for k, (s, thickness, medium) in enumerate(order, start=1):
        if s == len(surfaces) - 1:
            thickness = image_gap
        kw = {"index": k, "thickness": thickness}
        if medium == "mirror":
            kw["material"] = "mirror"
        elif medium != 1.0:
            kw["material"] = IdealMaterial(n=medium)
        radius = surfaces[s].get("radius", "flat")
        if not surfaces[s].get("stop") and radius != "flat":
            kw["radius"] = radius
        s_.surfaces.add(**kw)
    s_.surfaces.add(index=len(order) + 1)
    s_.set_aperture(aperture_type="EPD", value=10.0)
    s_.fields.set_type("angle")
    s_.fields.add(y=0)
    s_.wavelengths.add(value=D_LINE_UM, is_primary=True)
    return s_


print()
for name, pupil_diameter, paths, fields in GHOSTS:
    lens = tomllib.loads((ROOT / "configs" / "lenses" / f"{name}.toml").read_text())
    first_system = system(lens, 0.0, pupil_diameter, 1.0)
    back = float(first_system.paraxial.F2())
    entrance = float(first_system.paraxial.EPL())
    widest = max(s["semi_aperture"] for s in lens["surface"])
    for first, second in paths:
        s = ghost_system(lens, first, second, back)
        for degrees in fields:
            for px, py in GHOST_PUPIL:
                d = np.array([0.0, math.sin(math.radians(degrees)), math.cos(math.radians(degrees))])
                at = np.array([px * pupil_diameter / 2, py * pupil_diameter / 2, entrance])
                p = at - (entrance + widest + 1.0) / d[2] * d
                rays = RealRays(x=p[0:1], y=p[1:2], z=p[2:3], L=d[0:1], M=d[1:2], N=d[2:3],
                                intensity=np.ones(1), wavelength=np.full(1, D_LINE_UM))
                s.surface_group.trace(rays)
                x, y = float(rays.x[0]), float(rays.y[0])
                if math.isfinite(x) and math.isfinite(y):
                    print(f'("{name}", {pupil_diameter}, ({first}, {second}), {degrees}, ({px}, {py}), ({x:.9}, {y:.9})),')
