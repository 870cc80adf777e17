"""Ctrl-C stops a long call long before its end, through the session's
cancellation, and the package stays usable. The aim is a second; the
bounds asserted are generous (a loaded machine must not fail them), far
below the work's own length, so that a stop that waits for the work's end
fails."""

import os
import signal
import threading
import time

import numpy as np
import pytest

import aureole

# Timed: run alone (scripts/test), not beside other tests.
pytestmark = pytest.mark.latency


def interrupted(call, after):
    """Sends SIGINT `after` seconds into `call`; the seconds from the
    signal to the KeyboardInterrupt."""
    sent = []

    def interrupt():
        sent.append(time.monotonic())
        os.kill(os.getpid(), signal.SIGINT)

    # A process started in the background by a shell without job control
    # inherits SIGINT ignored, and Python then leaves it so: Ctrl-C is
    # Python's default handler, installed here for the call.
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(after, interrupt)
    try:
        timer.start()
        with pytest.raises(KeyboardInterrupt):
            call()
        stopped = time.monotonic()
    finally:
        timer.join()
        signal.signal(signal.SIGINT, before)
    return stopped - sent[0]


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
    # the exact near field.
    seconds = interrupted(lambda: camera.kernel(6001, 6001, image_width=36000), 0.5)
    assert seconds < 5.0, seconds
    # The camera still works afterwards.
    assert camera.kernel(33, 33).shape == (33, 33, 3)


def test_ctrl_c_stops_a_long_apply_before_its_end():
    # About 3.5 s on two cores, the kernel's build 2.5 of them: a stop
    # within 2 s of the signal, sent after 1 s, is before the end.
    camera = slow_camera()
    image = np.full((2160, 3840, 3), 0.05, np.float32)
    image[1000, 2000] = 1e5
    seconds = interrupted(lambda: camera.apply(image), 1.0)
    assert seconds < 2.0, seconds
