"""One job, one answer: the same request put to the command line
(`aureole apply`), the studio's API (`POST /api/export` on a running
`aureole studio`) and Python (`Camera.apply_file`) gets the same answer:
the same bytes, or the same refusal in the same words."""

import json
import math
import subprocess
import time
import urllib.error
import urllib.request

import pytest

import aureole

CONFIG = """threshold = 300.0
[[effect]]
type = "bloom"
epsilon = 0.05
beta = 2.0
radius = "2px"
[[effect]]
type = "corona"
epsilon = 0.05
rays = 6
length = "20px"
"""

# Lens ghosts traced through a shipped lens before a bloom: a stage of its
# own, which every front end runs the same way.
GHOSTS = """threshold = 300.0
[camera]
sensor_width_mm = 36.0
focal_length_mm = 50.0
f_number = 8.0
[[effect]]
type = "ghosts"
lens = "double-gauss-50mm-f1.4"
sources = 1
[[effect]]
type = "bloom"
epsilon = 0.05
beta = 2.0
radius = "2px"
"""

# name: (output extension, threshold, knee, glare only, layers), and
# whether every front end writes it. JSON has no NaN or infinity, so those
# thresholds are compared between the command line and Python alone
# (test_numbers_json_cannot_carry_are_refused_alike).
REQUESTS = {
    "the result": (("exr", None, 0.0, False, False), "written"),
    "a threshold and a knee": (("exr", 50.0, 0.5, False, False), "written"),
    "the glare alone": (("exr", None, 0.0, True, False), "written"),
    "the glare alone into a PFM": (("pfm", None, 0.0, True, False), "written"),
    "the glare layers": (("exr", None, 0.0, False, True), "written"),
    "the glare alone into Radiance HDR": (("hdr", None, 0.0, True, False), "refused"),
    "a negative threshold": (("exr", -1.0, 0.0, False, False), "refused"),
    "a negative knee": (("exr", None, -0.5, False, False), "refused"),
    "glare layers with the glare alone": (("exr", None, 0.0, True, True), "refused"),
    "glare layers into Radiance HDR": (("hdr", None, 0.0, False, True), "refused"),
    "glare layers into a picture": (("png", None, 0.0, False, True), "refused"),
}


@pytest.fixture(scope="module")
def studio(cli, street):
    """`aureole studio` on the street's folder: its address and token."""
    folder = street[0].parent
    process = subprocess.Popen(
        [cli, "-q", "studio", "--no-browser", "--device", "cpu", "--root", str(folder)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        url = process.stdout.readline().strip()
        assert url.startswith("http://"), process.stderr.read()
        address, token = url.split("/?token=")
        yield address, token
    finally:
        process.terminate()
        process.wait(timeout=10)


def answer_of_cli(cli, exr, output, request, camera="camera.toml"):
    _, threshold, knee, glare_only, layers = request
    args = [cli, "-q", "apply", str(exr), "-o", str(output), "--config", str(exr.parent / camera)]
    if threshold is not None:
        args.append(f"--threshold={threshold}")
    args.append(f"--knee={knee}")
    args += ["--glare-only"] * glare_only + ["--layers"] * layers
    done = subprocess.run(args, capture_output=True, text=True)
    if done.returncode != 0:
        assert done.returncode == 2, done.stderr
        return ("refused", done.stderr.strip().removeprefix("aureole: error: "))
    return ("written", output.read_bytes())


def answer_of_studio(studio, exr, output, request, config=CONFIG):
    address, token = studio
    _, threshold, knee, glare_only, layers = request
    body = {"image": str(exr), "config": config, "output": str(output), "knee": knee,
            "view": "glare" if glare_only else "result", "layers": layers}
    if threshold is not None:
        body["threshold"] = threshold

    def call(method, path, data=None):
        sent = urllib.request.Request(
            address + path, method=method, data=data,
            headers={"Authorization": f"Bearer {token}", "Content-Type": "application/json"})
        try:
            with urllib.request.urlopen(sent, timeout=60) as reply:
                return reply.status, json.load(reply)
        except urllib.error.HTTPError as error:
            return error.code, json.load(error)

    status, reply = call("POST", "/api/export", json.dumps(body).encode())
    if status != 200:
        assert status == 400, reply
        return ("refused", reply["error"])
    while True:
        _, progress = call("GET", f"/api/export/{reply['job']}")
        if progress["done"]:
            break
        time.sleep(0.02)
    if progress["error"]:
        return ("refused", progress["error"])
    return ("written", output.read_bytes())


def answer_of_python(exr, output, request, config=CONFIG):
    _, threshold, knee, glare_only, layers = request
    camera = aureole.Camera.from_toml(config)
    try:
        camera.apply_file(exr, output, threshold=threshold, knee=knee, glare_only=glare_only,
                          layers=layers)
    except ValueError as error:
        return ("refused", str(error))
    return ("written", output.read_bytes())


@pytest.fixture(scope="module")
def scene(street, tmp_path_factory):
    """The street and the camera's TOML beside it, in the studio's root."""
    exr = street[0]
    (exr.parent / "camera.toml").write_text(CONFIG)
    (exr.parent / "ghosts.toml").write_text(GHOSTS)
    return exr, tmp_path_factory.mktemp("answers")


@pytest.mark.parametrize("name", REQUESTS)
def test_the_same_request_gets_the_same_answer_from_every_front_end(cli, studio, scene, name):
    exr, folder = scene
    request, expected = REQUESTS[name]
    # The studio writes under its root only: every output goes there.
    outputs = {end: exr.parent / f"{name.replace(' ', '-')}.{end}.{request[0]}"
               for end in ("cli", "studio", "python")}
    answers = {
        "cli": answer_of_cli(cli, exr, outputs["cli"], request),
        "studio": answer_of_studio(studio, exr, outputs["studio"], request),
        "python": answer_of_python(exr, outputs["python"], request),
    }
    kinds = {end: kind for end, (kind, _) in answers.items()}
    assert len(set(kinds.values())) == 1, kinds
    if kinds["cli"] == "written":
        assert answers["studio"][1] == answers["cli"][1], "the studio wrote other bytes"
        assert answers["python"][1] == answers["cli"][1], "Python wrote other bytes"
    else:
        # The words name the output, which differs: compare what follows.
        words = {end: line.replace(str(outputs[end]), "OUTPUT") for end, (_, line) in answers.items()}
        assert words["studio"] == words["cli"] and words["python"] == words["cli"], words
        for output in outputs.values():
            assert not output.exists()
    assert kinds["cli"] == expected, answers["cli"]


@pytest.mark.parametrize("threshold", [math.nan, math.inf])
def test_numbers_json_cannot_carry_are_refused_alike(cli, scene, threshold):
    exr, folder = scene
    request = ("exr", threshold, 0.0, False, False)
    cli_answer = answer_of_cli(cli, exr, folder / "cli.exr", request)
    python_answer = answer_of_python(exr, folder / "python.exr", request)
    assert cli_answer[0] == python_answer[0] == "refused"
    assert cli_answer[1] == python_answer[1], (cli_answer, python_answer)
    assert cli_answer[1].startswith("apply: threshold = ")


def test_lens_ghosts_get_the_same_bytes_from_every_front_end(cli, studio, scene):
    exr, _ = scene
    request = ("exr", None, 0.0, False, True)
    outputs = {end: exr.parent / f"ghosts.{end}.exr" for end in ("cli", "studio", "python")}
    answers = {
        "cli": answer_of_cli(cli, exr, outputs["cli"], request, camera="ghosts.toml"),
        "studio": answer_of_studio(studio, exr, outputs["studio"], request, config=GHOSTS),
        "python": answer_of_python(exr, outputs["python"], request, config=GHOSTS),
    }
    assert {kind for kind, _ in answers.values()} == {"written"}, answers
    assert answers["studio"][1] == answers["cli"][1], "the studio wrote other bytes"
    assert answers["python"][1] == answers["cli"][1], "Python wrote other bytes"
    ghosts, _ = aureole.read(outputs["cli"], layer="glare.ghosts")
    assert ghosts.max() > 0


def test_lens_ghosts_in_memory_have_their_layer_and_their_figures(scene, tmp_path):
    exr, _ = scene
    assert "double-gauss-50mm-f1.4" in dict(aureole.lenses())
    image, _ = aureole.read(exr)
    camera = aureole.Camera.from_toml(GHOSTS)
    result, layers = camera.apply(image, layers=True)
    assert list(layers) == ["glare.ghosts", "glare.bloom", "glare"]
    assert layers["glare.ghosts"].max() > 0
    report = camera.apply_file(exr, tmp_path / "out.exr")
    assert report["ghosts"]["traced"] == 1 and report["ghosts"]["paths"] == 78
    assert 0 < report["ghosts"]["light"] < 1e-2
