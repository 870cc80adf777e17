"""Ctrl-C stops a long call long before its end, through the session's
cancellation, and the package stays usable. No clock: the signal is sent
once the work reports progress, and the work's own progress after the
interrupt shows where it stopped (docs/python.md gives the measured
delay: well under a second)."""

import os
import signal
import threading

import numpy as np
import pytest

import aureole

# Run alone (scripts/test): the signal goes to the whole process.
pytestmark = pytest.mark.latency


def interrupted(call):
    """Runs `call(progress)` and sends SIGINT from another thread once the
    work reports progress (it is then under way, whatever the machine's
    load); returns the furthest fraction reported, per stage, after the
    KeyboardInterrupt."""
    seen = {}
    started = threading.Event()

    def progress(stage, done):
        seen[stage] = max(seen.get(stage, 0.0), done)
        if done > 0.0:
            started.set()

    def interrupt():
        started.wait()
        os.kill(os.getpid(), signal.SIGINT)

    # A process started in the background by a shell without job control
    # inherits SIGINT ignored, and Python then leaves it so: Ctrl-C is
    # Python's default handler, installed here for the call.
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    sender = threading.Thread(target=interrupt)
    try:
        sender.start()
        with pytest.raises(KeyboardInterrupt):
            call(progress)
    finally:
        started.set()
        sender.join()
        signal.signal(signal.SIGINT, before)
    return seen


def slow_camera():
    """A lens whose kernels take seconds: rounded blades, 112 edges summed
    at every point of the exact near field, in 17 wavelengths."""
    return aureole.Camera.from_toml("""
[camera]
sensor_width_mm = 36
focal_length_mm = 50
f_number = 8

[[effect]]
type = "aperture"
blades = 7
roundness = 0.5
""")


def test_ctrl_c_stops_a_long_kernel_before_its_end():
    camera = slow_camera()
    # About 20 s of work on two cores: 1 µm pixels put 440 000 pixels in
    # the exact near field. Interrupted as soon as it reports progress, it
    # stops with most of the work not done.
    seen = interrupted(lambda progress: camera.kernel(
        6001, 6001, image_width=36000, progress=progress))
    assert seen and max(seen.values()) < 0.5, seen
    # The camera still works afterwards.
    assert camera.kernel(33, 33).shape == (33, 33, 3)


def test_ctrl_c_stops_a_long_apply_before_its_end():
    # About 3.5 s on two cores, the kernel's build 2.5 of them: interrupted
    # once under way, it never reaches the convolution's end.
    camera = slow_camera()
    image = np.full((2160, 3840, 3), 0.05, np.float32)
    image[1000, 2000] = 1e5
    seen = interrupted(lambda progress: camera.apply(image, progress=progress))
    assert seen and seen.get("convolving", 0.0) < 1.0, seen
