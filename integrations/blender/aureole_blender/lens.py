"""The scene camera as aureole sees it: Blender's camera and render
settings turned into an aureole camera (TOML), with no Blender in sight so
that it can be read and tested on its own."""

import math
from dataclasses import dataclass

# One unit of Blender's scene-linear radiance, in cd/m². Blender's watts are
# radiometric watts at 683 lm/W (the SI candela's efficacy at 555 nm): an
# emission shader of strength 1 renders 1.0 and sends 1 W/(m²·sr), i.e.
# 683 cd/m². Blender's own glTF exporter converts its lights with the same
# factor (io_scene_gltf2, PBR_WATTS_TO_LUMENS = 683, its "Standard"
# lighting mode).
BLENDER_UNIT_CD_M2 = 683.0


class LensError(ValueError):
    """A camera aureole cannot stand in for, said in one line."""


@dataclass(frozen=True)
class Lens:
    """What aureole needs of a Blender camera and its render settings."""

    blades: int  # dof.aperture_blades: 0 a round stop, else 3 or more
    f_number: float  # dof.aperture_fstop
    rotation_rad: float  # dof.aperture_rotation
    ratio: float  # dof.aperture_ratio (anamorphic bokeh)
    focal_length_mm: float  # lens
    sensor_width_mm: float
    sensor_height_mm: float
    sensor_fit: str  # AUTO, HORIZONTAL or VERTICAL
    width_px: int  # the rendered image: resolution × percentage, cropped
    height_px: int
    pixel_aspect: float = 1.0  # pixel_aspect_x / pixel_aspect_y
    kind: str = "PERSP"

    def sensor_span_mm(self):
        """The width of the sensor the image's width spans (what aureole
        calls sensor_width_mm: the pixel pitch is this over the width in
        pixels), after Blender's sensor fit."""
        width = self.width_px * self.pixel_aspect
        height = float(self.height_px)
        fit = self.sensor_fit
        if fit == "AUTO":
            # Blender's sensor width spans the larger side.
            return self.sensor_width_mm if width >= height else self.sensor_width_mm * width / height
        if fit == "HORIZONTAL":
            return self.sensor_width_mm
        if fit == "VERTICAL":
            return self.sensor_height_mm * width / height
        raise LensError(f"sensor fit {fit!r}: allowed AUTO, HORIZONTAL, VERTICAL")

    def rotation_deg(self):
        """aureole's rotation of the stop: at 0 aureole puts a blade's tip on
        +x, Cycles (regular_polygon_sample) the middle of a side; both turn
        counter-clockwise on the picture."""
        turn = math.degrees(self.rotation_rad)
        if self.blades >= 3:
            turn += 180.0 / self.blades
        return turn

    def notes(self):
        """What Blender's camera has that aureole's stop does not model."""
        notes = []
        if abs(self.ratio - 1.0) > 1e-6:
            notes.append(
                f"aperture ratio {self.ratio:g}: the stop's anamorphic squeeze is not modelled; "
                "its diffraction is that of the unsqueezed stop")
        return notes

    def check(self):
        if self.kind != "PERSP":
            kind = {"ORTHO": "orthographic", "PANO": "panoramic"}.get(self.kind, self.kind.lower())
            raise LensError(f"the camera is {kind}: aureole models a perspective lens's stop")
        if self.blades != 0 and not 3 <= self.blades <= 64:
            raise LensError(f"aperture blades {self.blades}: allowed 0 (a round stop) or 3 to 64")
        if abs(self.pixel_aspect - 1.0) > 1e-6:
            raise LensError(
                f"pixel aspect {self.pixel_aspect:g}: aureole's pixels are square (set X and Y to 1)")
        for name, value in (("f-stop", self.f_number), ("focal length", self.focal_length_mm),
                            ("sensor size", self.sensor_span_mm())):
            if not value > 0:
                raise LensError(f"{name} {value:g}: must be positive")

    def toml(self):
        """The camera as an aureole config: the sensor, the lens and its
        stop's diffraction (`aureole apply --config` with it gives what the
        add-on gives)."""
        self.check()
        return (
            "# The scene camera, as the aureole Blender add-on reads it.\n"
            "[camera]\n"
            f"sensor_width_mm = {self.sensor_span_mm()!r}\n"
            f"focal_length_mm = {float(self.focal_length_mm)!r}\n"
            f"f_number = {float(self.f_number)!r}\n"
            "\n"
            "[[effect]]\n"
            'type = "aperture"\n'
            f"blades = {int(self.blades)}\n"
            f"rotation_deg = {self.rotation_deg()!r}\n"
        )


def ghosts_toml(name):
    """The ghosts of the shipped lens `name` (aureole.lenses()), as a
    config: traced at the camera's focal length and f-stop, which the scene
    camera or the effects give."""
    return f'[[effect]]\ntype = "ghosts"\nlens = "{name}"\n'
