"""Ctrl-C stops a long call within a second, through the session's
cancellation, and the package stays usable."""

import os
import signal
import threading
import time

import numpy as np
import pytest

import aureole


def interrupted(call, after):
    """Sends SIGINT `after` seconds into `call`; the seconds from the
    signal to the KeyboardInterrupt."""
    sent = []

    def interrupt():
        sent.append(time.monotonic())
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(after, interrupt)
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        call()
    stopped = time.monotonic()
    timer.join()
    return stopped - sent[0]


def test_ctrl_c_stops_a_long_kernel_within_a_second():
    camera = aureole.Camera.preset("camera-f8-7blade")
    # Minutes of work on two cores.
    seconds = interrupted(lambda: camera.kernel(6001, 6001, image_width=12000), 0.5)
    assert seconds < 1.0, seconds
    # The camera still works afterwards.
    assert camera.kernel(33, 33).shape == (33, 33, 3)


def test_ctrl_c_stops_a_long_apply_within_a_second():
    camera = aureole.Camera.preset("camera-f8-7blade")
    image = np.full((2160, 3840, 3), 0.05, np.float32)
    image[1000, 2000] = 1e5
    seconds = interrupted(lambda: camera.apply(image), 1.0)
    assert seconds < 1.0, seconds
