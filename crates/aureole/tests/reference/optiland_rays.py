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
