"""The paraxial data of every shipped lens (crates/aureole/lenses/) against
optiland, an optical design library nobody here wrote, tracing the same
prescription: `aureole lens --json` and optiland's paraxial focal length,
back focus and entrance pupil agree to 1e-9 of the focal length. An
anamorphic lens's cylinders are optiland's toroidal surfaces, whose
paraxial trace is in the y–z plane; turned a quarter turn (x and y
radii swapped), the same lens gives the x–z plane's."""

import json
import pathlib
import subprocess
import tomllib

import pytest

from conftest import ROOT

optic = pytest.importorskip("optiland.optic")
materials = pytest.importorskip("optiland.materials")

LENSES = sorted((ROOT / "crates" / "aureole" / "lenses").glob("*.toml"))
D_LINE_UM = 0.5875618


def radius(value):
    return float("inf") if value in (None, "flat") else float(value)


def optiland_of(path, turned=False):
    """The prescription in `path` as an optiland system at the d line;
    `turned`, a quarter turn about the axis."""
    lens = tomllib.loads(path.read_text())
    system = optic.Optic()
    system.surfaces.add(index=0, thickness=float("inf"))
    for i, s in enumerate(lens["surface"], start=1):
        surface = {"index": i, "thickness": s.get("thickness", 0.0)}
        if s.get("stop"):
            surface["is_stop"] = True
        elif "radius_y" in s:
            across = [radius(s.get("radius")), radius(s["radius_y"])]
            if turned:
                across.reverse()
            surface.update(surface_type="toroidal", radius_x=across[0], radius_y=across[1])
        elif s.get("radius", "flat") != "flat":
            surface["radius"] = s["radius"]
        if "n_d" in s and not s.get("stop"):
            surface["material"] = materials.IdealMaterial(n=s["n_d"])
        system.surfaces.add(**surface)
    system.surfaces.add(index=len(lens["surface"]) + 1)
    system.set_aperture(aperture_type="EPD", value=10.0)
    system.fields.set_type("angle")
    system.fields.add(y=0)
    system.wavelengths.add(value=D_LINE_UM, is_primary=True)
    return lens, system


def test_there_are_shipped_lenses():
    assert len(LENSES) >= 5


@pytest.mark.parametrize("path", LENSES, ids=[p.stem for p in LENSES])
def test_first_order_data_agree_with_optiland(cli, path):
    done = subprocess.run([cli, "lens", str(path), "--json"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    ours = json.loads(done.stdout)
    lens, system = optiland_of(path)
    paraxial = system.paraxial
    f = paraxial.f2()
    # optiland places the image at the last thickness; its F2 is the back
    # focal point from there.
    back = lens["surface"][-1].get("thickness", 0.0) + paraxial.F2()
    for name, theirs in [("focal_length", f), ("back_focus", back),
                         ("entrance_pupil", paraxial.EPL())]:
        assert abs(ours[name] - float(theirs)) < 1e-9 * abs(f), (name, ours[name], theirs)
    _, turned = optiland_of(path, turned=True)
    x = turned.paraxial
    for name, theirs in [("focal_length_x", x.f2()),
                         ("back_focus_x", lens["surface"][-1].get("thickness", 0.0) + x.F2())]:
        assert abs(ours[name] - float(theirs)) < 1e-9 * abs(f), (name, ours[name], theirs)
    assert abs(ours["squeeze"] - ours["focal_length"] / ours["focal_length_x"]) < 1e-12
