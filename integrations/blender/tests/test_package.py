"""The add-on's two packages (package.py): a Blender 4.2+ extension whose
manifest names the wheel it carries, and a legacy add-on carrying the
aureole package, both from the wheel scripts/test builds."""

import pathlib
import subprocess
import sys
import tomllib
import zipfile

import pytest

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[2]


@pytest.fixture(scope="module")
def packages(tmp_path_factory):
    wheels = sorted((ROOT / "target" / "wheels").glob("aureole-*.whl"))
    if not wheels:
        pytest.skip("no aureole wheel: pip wheel --no-deps -w target/wheels ./crates/aureole-py")
    out = tmp_path_factory.mktemp("dist")
    subprocess.run([sys.executable, HERE.parent / "package.py", "--wheel", wheels[-1],
                    "--out", out], check=True, capture_output=True)
    return wheels[-1], next(out.glob("*-extension.zip")), next(out.glob("*-legacy.zip"))


def test_the_extension_names_the_wheel_it_carries(packages):
    wheel, extension, _ = packages
    with zipfile.ZipFile(extension) as z:
        names = set(z.namelist())
        manifest = tomllib.loads(z.read("blender_manifest.toml").decode())
    assert {"__init__.py", "lens.py", "jobs.py"} <= names
    assert manifest["schema_version"] == "1.0.0"
    assert manifest["type"] == "add-on" and manifest["id"] == "aureole_blender"
    assert manifest["blender_version_min"] == "4.2.0"
    assert len(manifest["tagline"]) <= 64 and not manifest["tagline"].endswith(".")
    assert all(entry.startswith("SPDX:") for entry in manifest["license"])
    assert manifest["wheels"] == [f"./wheels/{wheel.name}"]
    assert f"wheels/{wheel.name}" in names
    assert manifest["platforms"] == ["linux-x64"] or sys.platform != "linux"


def test_the_legacy_add_on_carries_the_package(packages, tmp_path):
    _, _, legacy = packages
    with zipfile.ZipFile(legacy) as z:
        z.extractall(tmp_path)
    vendor = tmp_path / "aureole_blender" / "vendor"
    done = subprocess.run(
        [sys.executable, "-c", "import aureole; print(aureole.__file__, len(aureole.presets()))"],
        capture_output=True, text=True, env={"PYTHONPATH": str(vendor)}, check=True)
    assert str(vendor) in done.stdout
    assert (tmp_path / "aureole_blender" / "__init__.py").is_file()
