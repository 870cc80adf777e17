"""Shared fixtures: the command-line binary to compare with, and a small
night scene written by it."""

import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def cli():
    """The `aureole` binary (AUREOLE_BIN, else the workspace's release or
    debug build)."""
    for candidate in (os.environ.get("AUREOLE_BIN"),
                      ROOT / "target" / "release" / "aureole",
                      ROOT / "target" / "debug" / "aureole"):
        if candidate and pathlib.Path(candidate).is_file():
            return str(candidate)
    pytest.fail("no aureole binary: cargo build --release -p aureole-cli, or set AUREOLE_BIN")


def run(cli, *args):
    done = subprocess.run([cli, "-q", *map(str, args)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return done


@pytest.fixture(scope="session")
def street(cli, tmp_path_factory):
    """The built-in night street, 192×108, as a float EXR and a PFM."""
    folder = tmp_path_factory.mktemp("street")
    exr = folder / "street.exr"
    run(cli, "demo", "--size", "192x108", "--hdr", exr, "-o", folder / "street.png")
    pfm = folder / "street.pfm"
    run(cli, "apply", exr, "-o", pfm, "--config", write_identity(folder))
    return exr, pfm


def write_identity(folder):
    """A camera that moves no light (a bloom of ε = 0), to convert files."""
    path = folder / "identity.toml"
    path.write_text('[[effect]]\ntype = "bloom"\nradius = "1px"\nbeta = 2\nepsilon = 0\n')
    return path
