"""Fisheye HDR scenes rendered by Radiance (the PyPI `pyradiance` wheel's
`gensky`, `oconv` and `rpict`), for comparing `aureole glare` with Radiance's
own `evalglare` on the very same files.

Each scene is a plain Radiance description: an office with a sunlit window,
the same office under an overcast sky, a night street with lamps, a room
with ceiling luminaires and a view towards the low sun. Every one is seen
through a 180° angular fisheye (`-vta`), as daylight glare studies render.
"""

import os
import subprocess
from pathlib import Path


def radiance_bin():
    """The directory of pyradiance's Radiance binaries, or None."""
    try:
        import pyradiance
    except ImportError:
        return None
    root = Path(pyradiance.__file__).parent
    return root / "bin" if (root / "bin" / "evalglare").exists() else None


def _env(bindir):
    env = dict(os.environ)
    env["PATH"] = f"{bindir}{os.pathsep}{env.get('PATH', '')}"
    env["RAYPATH"] = f".{os.pathsep}{bindir.parent / 'lib'}"
    return env


def run(bindir, args, cwd, stdin=None):
    """Runs a Radiance tool; its standard output as bytes."""
    done = subprocess.run(
        args, cwd=cwd, env=_env(bindir), input=stdin, capture_output=True, check=False
    )
    if done.returncode != 0:
        raise RuntimeError(f"{args[0]} failed: {done.stderr.decode(errors='replace')}")
    return done.stdout


def _poly(material, name, *points):
    coords = " ".join(f"{c:g}" for p in points for c in p)
    return f"{material} polygon {name}\n0\n0\n{3 * len(points)} {coords}\n"


def _box(material, name, x0, y0, z0, x1, y1, z1):
    faces = [
        ((x0, y0, z0), (x0, y1, z0), (x1, y1, z0), (x1, y0, z0)),
        ((x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)),
        ((x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)),
        ((x0, y1, z0), (x0, y1, z1), (x1, y1, z1), (x1, y1, z0)),
        ((x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)),
        ((x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)),
    ]
    return "".join(_poly(material, f"{name}_{i}", *f) for i, f in enumerate(faces))


MATERIALS = """
void plastic wall 0 0 5 .55 .55 .52 0 0
void plastic floor 0 0 5 .25 .22 .2 0 0
void plastic ceiling 0 0 5 .8 .8 .8 0 0
void plastic ground_mat 0 0 5 .15 .15 .15 0 0
void plastic facade 0 0 5 .35 .32 .3 0 0
void glass pane 0 0 3 .9 .9 .9
"""

SKY = """
skyfunc glow sky_glow 0 0 4 1 1 1 0
sky_glow source sky 0 0 4 0 0 1 180
skyfunc glow ground_glow 0 0 4 1 .8 .5 0
ground_glow source ground 0 0 4 0 0 -1 180
"""


def _office():
    """A 6 × 5 × 3 m office, its window (4 × 1.8 m) in the south wall
    (y = 0), a floor outside."""
    s = MATERIALS
    s += _poly("floor", "floor", (0, 0, 0), (6, 0, 0), (6, 5, 0), (0, 5, 0))
    s += _poly("ceiling", "ceil", (0, 0, 3), (0, 5, 3), (6, 5, 3), (6, 0, 3))
    s += _poly("wall", "north", (0, 5, 0), (6, 5, 0), (6, 5, 3), (0, 5, 3))
    s += _poly("wall", "west", (0, 0, 0), (0, 5, 0), (0, 5, 3), (0, 0, 3))
    s += _poly("wall", "east", (6, 0, 0), (6, 0, 3), (6, 5, 3), (6, 5, 0))
    s += _poly("wall", "s_low", (0, 0, 0), (0, 0, 0.8), (6, 0, 0.8), (6, 0, 0))
    s += _poly("wall", "s_high", (0, 0, 2.6), (0, 0, 3), (6, 0, 3), (6, 0, 2.6))
    s += _poly("wall", "s_left", (0, 0, 0.8), (0, 0, 2.6), (1, 0, 2.6), (1, 0, 0.8))
    s += _poly("wall", "s_right", (5, 0, 0.8), (5, 0, 2.6), (6, 0, 2.6), (6, 0, 0.8))
    s += _poly("pane", "window", (1, 0, 0.8), (1, 0, 2.6), (5, 0, 2.6), (5, 0, 0.8))
    s += _poly("ground_mat", "outside", (-50, -60, -0.01), (56, -60, -0.01), (56, 0, -0.01), (-50, 0, -0.01))
    return s


def _street():
    """A 12 m street between façades, lamps on 6 m posts every 20 m."""
    s = MATERIALS
    s += "void light lamp 0 0 3 600 560 480\n"
    s += "void glow night_sky 0 0 4 .0004 .0005 .0009 0\nnight_sky source dark 0 0 4 0 0 1 180\n"
    s += _poly("ground_mat", "road", (-6, -10, 0), (6, -10, 0), (6, 200, 0), (-6, 200, 0))
    s += _box("facade", "left", -20, -10, 0, -8, 200, 15)
    s += _box("facade", "right", 8, -10, 0, 20, 200, 12)
    for i, y in enumerate(range(10, 170, 20)):
        for side, x in (("l", -5.5), ("r", 5.5)):
            s += f"lamp sphere lamp_{side}{i}\n0\n0\n4 {x} {y} 6 0.18\n"
    return s


def _luminaires():
    """An 8 × 6 × 3 m room with six 0.6 m square ceiling luminaires."""
    s = MATERIALS
    s += "void light panel 0 0 3 28 28 26\n"
    s += _poly("floor", "floor", (0, 0, 0), (8, 0, 0), (8, 6, 0), (0, 6, 0))
    s += _poly("ceiling", "ceil", (0, 0, 3), (0, 6, 3), (8, 6, 3), (8, 0, 3))
    s += _box("wall", "room", 0, 0, 0, 8, 6, 3)
    for i, (x, y) in enumerate((x, y) for x in (2, 4, 6) for y in (2.5, 4.5)):
        a, b = x - 0.3, y - 0.3
        s += _poly("panel", f"lum{i}", (a, b, 2.99), (a, b + 0.6, 2.99), (a + 0.6, b + 0.6, 2.99), (a + 0.6, b, 2.99))
    return s


def _low_sun():
    """Open ground with a few buildings, looking towards a low winter sun."""
    s = MATERIALS
    s += _poly("ground_mat", "ground", (-500, -500, 0), (500, -500, 0), (500, 500, 0), (-500, 500, 0))
    s += _box("facade", "b1", -80, -30, 0, -60, -10, 18)
    s += _box("facade", "b2", 15, -70, 0, 35, -50, 9)
    s += _box("facade", "b3", -10, 40, 0, 10, 60, 25)
    return s


# name: (gensky arguments or None, geometry, view, rpict's ambient options)
SCENES = {
    "office-sun": (
        ["3", "21", "10", "+s", "-a", "47", "-o", "-8", "-m", "-15"],
        _office,
        "-vta -vp 3 3.8 1.2 -vd 0 -1 0 -vu 0 0 1 -vh 180 -vv 180",
        ["-ab", "1", "-ad", "512", "-as", "0", "-aa", "0.15", "-ar", "64"],
    ),
    "office-overcast": (
        ["3", "21", "10", "-c", "-a", "47", "-o", "-8", "-m", "-15", "-B", "90"],
        _office,
        "-vta -vp 3 3.8 1.2 -vd 0 -1 0 -vu 0 0 1 -vh 180 -vv 180",
        ["-ab", "1", "-ad", "512", "-as", "0", "-aa", "0.15", "-ar", "64"],
    ),
    "night-street": (
        None,
        _street,
        "-vta -vp 0 0 1.6 -vd 0 1 0 -vu 0 0 1 -vh 180 -vv 180",
        ["-ab", "0", "-av", ".02", ".02", ".02"],
    ),
    "ceiling-luminaires": (
        None,
        _luminaires,
        "-vta -vp 4 0.6 1.2 -vd 0 1 0 -vu 0 0 1 -vh 180 -vv 180",
        ["-ab", "0", "-av", "3", "3", "3"],
    ),
    "low-sun": (
        ["12", "21", "15.3", "+s", "-a", "47", "-o", "-8", "-m", "-15"],
        _low_sun,
        "-vta -vp 0 0 1.6 -vd -0.35 -0.94 0.05 -vu 0 0 1 -vh 180 -vv 180",
        ["-ab", "0", "-av", "2", "2", "2"],
    ),
}


def render(bindir, name, out_dir, size=400, view=None, height=None):
    """Renders scene `name` to `out_dir/name.hdr` (a `size`² angular
    fisheye with its VIEW in the header, or `size` × `height` through
    `view`, Radiance's options with the scene's position and direction);
    returns the path."""
    sky_args, geometry, scene_view, ambient = SCENES[name]
    if view is None:
        view = scene_view
    else:
        view = " ".join(w for w in scene_view.split() if not w.startswith("-vt")) + " " + view
    work = Path(out_dir)
    scene = geometry()
    if sky_args:
        scene = run(bindir, ["gensky", *sky_args], work).decode() + SKY + scene
    (work / f"{name}.rad").write_text(scene)
    octree = run(bindir, ["oconv", f"{name}.rad"], work)
    (work / f"{name}.oct").write_bytes(octree)
    picture = run(
        bindir,
        ["rpict", *view.split(), "-x", str(size), "-y", str(height or size), "-ps", "1", "-dj", "0", "-ds", ".1",
         *ambient, f"{name}.oct"],
        work,
    )
    path = work / f"{name}.hdr"
    path.write_bytes(picture)
    return path


def write_rgbe(path, rgb, view):
    """Writes `rgb` ((H, W, 3) floats in Radiance's units) as a flat
    (uncompressed) Radiance picture with `view` in its VIEW line."""
    import numpy as np

    rgb = np.asarray(rgb, dtype=np.float64)
    height, width = rgb.shape[:2]
    peak = rgb.max(axis=2)
    mantissa, exponent = np.frexp(peak)
    scale = np.where(peak > 1e-32, mantissa * 256.0 / np.where(peak > 0, peak, 1), 0.0)
    pixels = np.zeros((height, width, 4), dtype=np.uint8)
    pixels[..., :3] = np.clip(rgb * scale[..., None], 0, 255).astype(np.uint8)
    pixels[..., 3] = np.where(peak > 1e-32, exponent + 128, 0).astype(np.uint8)
    header = f"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nVIEW= {view}\n\n-Y {height} +X {width}\n"
    Path(path).write_bytes(header.encode() + pixels.tobytes())


def fisheye_from_panorama(panorama, size, azimuth_deg):
    """A 180° angular fisheye (`size`²) looking level at `azimuth_deg` out
    of an equirectangular panorama ((H, W, 3), azimuth 0 at its left edge
    growing to the right, elevation +90° at its top), nearest samples."""
    import numpy as np

    height, width = panorama.shape[:2]
    centre = (np.arange(size) + 0.5) / size - 0.5
    x, y = np.meshgrid(centre * np.pi, -centre * np.pi)
    r = np.hypot(x, y)
    theta = r
    with np.errstate(invalid="ignore", divide="ignore"):
        ux, uy = np.where(r > 0, x / r, 0.0), np.where(r > 0, y / r, 0.0)
    # Camera frame: z ahead (level, at the azimuth), y up, x right.
    cx, cy, cz = np.sin(theta) * ux, np.sin(theta) * uy, np.cos(theta)
    az = np.radians(azimuth_deg)
    # Ahead is (sin az, cos az, 0), right is (cos az, −sin az, 0).
    wx = cz * np.sin(az) + cx * np.cos(az)
    wy = cz * np.cos(az) - cx * np.sin(az)
    wz = cy
    azimuth = np.mod(np.arctan2(wx, wy), 2 * np.pi)
    elevation = np.arcsin(np.clip(wz, -1, 1))
    col = np.clip((azimuth / (2 * np.pi) * width).astype(int), 0, width - 1)
    row = np.clip(((0.5 - elevation / np.pi) * height).astype(int), 0, height - 1)
    out = panorama[row, col]
    out[theta > np.pi / 2] = 0.0
    return out
