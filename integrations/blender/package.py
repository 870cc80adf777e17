#!/usr/bin/env python3
"""Packs the Blender add-on with an aureole wheel, two ways:

  aureole_blender-VERSION-extension.zip  a Blender 4.2+ extension: the add-on,
      its manifest naming the wheel, and the wheel (Blender installs it);
  aureole_blender-VERSION-legacy.zip     a legacy add-on for Blender 3.x: the
      add-on folder with the wheel's aureole package in vendor/.

  python3 integrations/blender/package.py --wheel target/wheels/aureole-….whl --out dist/

The wheel must suit the Blender it goes to: its Python (3.11 for Blender 3.4
to 4.5) and platform."""

import argparse
import pathlib
import re
import sys
import zipfile

HERE = pathlib.Path(__file__).resolve().parent
ADDON = HERE / "aureole_blender"
SOURCES = ("__init__.py", "lens.py", "jobs.py")


def version():
    text = (ADDON / "blender_manifest.toml").read_text()
    return re.search(r'^version = "([^"]+)"', text, re.M).group(1)


# A wheel's platform tag, as Blender's manifest names the platform.
PLATFORMS = (("manylinux", "x86_64", "linux-x64"), ("linux", "x86_64", "linux-x64"),
             ("manylinux", "aarch64", "linux-arm64"), ("linux", "aarch64", "linux-arm64"),
             ("macosx", "arm64", "macos-arm64"), ("macosx", "x86_64", "macos-x64"),
             ("win", "amd64", "windows-x64"), ("win", "arm64", "windows-arm64"))


def platform(wheel):
    tag = wheel.stem.split("-")[-1]
    for system, machine, name in PLATFORMS:
        if tag.startswith(system) and tag.endswith(machine):
            return name
    sys.exit(f"package.py: {wheel.name}: a platform Blender's extensions do not name ({tag})")


def extension(wheel, out):
    path = out / f"aureole_blender-{version()}-extension.zip"
    manifest = (ADDON / "blender_manifest.toml").read_text()
    # The wheel holds compiled code: the extension is for its platform only.
    manifest = manifest.replace(
        "wheels = []", f'platforms = ["{platform(wheel)}"]\nwheels = ["./wheels/{wheel.name}"]')
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for name in SOURCES:
            z.write(ADDON / name, name)
        z.writestr("blender_manifest.toml", manifest)
        z.write(wheel, f"wheels/{wheel.name}")
    return path


def legacy(wheel, out):
    path = out / f"aureole_blender-{version()}-legacy.zip"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z, zipfile.ZipFile(wheel) as w:
        for name in SOURCES:
            z.write(ADDON / name, f"aureole_blender/{name}")
        for item in w.infolist():
            if item.filename.startswith("aureole/"):
                z.writestr(f"aureole_blender/vendor/{item.filename}", w.read(item))
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--wheel", required=True, type=pathlib.Path,
                        help="the aureole wheel (maturin build --release, or pip wheel "
                             "./crates/aureole-py)")
    parser.add_argument("--out", default=pathlib.Path("dist"), type=pathlib.Path)
    args = parser.parse_args()
    if not zipfile.is_zipfile(args.wheel):
        sys.exit(f"package.py: {args.wheel}: not a wheel (a zip file)")
    args.out.mkdir(parents=True, exist_ok=True)
    for path in (extension(args.wheel, args.out), legacy(args.wheel, args.out)):
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
