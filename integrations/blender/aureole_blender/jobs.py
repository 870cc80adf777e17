"""Frames through aureole on a thread of their own, so that Blender's
interface never waits on them: one job per frame, done in order, each
cancellable. Nothing here touches bpy (it is not thread-safe); the add-on's
timer reads the jobs' state."""

import collections
import pathlib
import threading
from dataclasses import dataclass, field
from typing import Optional


class Cancelled(Exception):
    """Raised from aureole's progress callback to stop a frame."""


@dataclass
class Job:
    """One frame: `source` (an EXR Blender wrote) through `camera` into
    `output`."""

    source: pathlib.Path
    output: pathlib.Path
    camera: object  # aureole.Camera
    options: dict  # apply_file's keyword arguments
    state: str = "queued"  # queued, running, done, failed, cancelled
    stage: str = ""
    fraction: float = 0.0
    message: str = ""
    result: Optional[dict] = None
    reported: bool = False  # said and shown by the add-on, once finished
    cancel: threading.Event = field(default_factory=threading.Event)

    @property
    def finished(self):
        return self.state in ("done", "failed", "cancelled")

    def run(self):
        if self.cancel.is_set():
            self.state = "cancelled"
            return
        self.state = "running"

        def progress(stage, fraction):
            # aureole calls this from the applying thread; raising stops
            # the work (and deletes nothing: outputs are written whole).
            if self.cancel.is_set():
                raise Cancelled()
            self.stage, self.fraction = stage, fraction

        try:
            self.output.parent.mkdir(parents=True, exist_ok=True)
            self.result = self.camera.apply_file(
                self.source, self.output, progress=progress, **self.options)
        except Exception as error:  # noqa: BLE001 - every failure is the user's to read
            if self.cancel.is_set():
                self.state, self.message = "cancelled", "cancelled"
            else:
                self.state, self.message = "failed", str(error).strip().splitlines()[0]
            return
        self.state, self.fraction = "done", 1.0


class Runner:
    """Jobs done one after another on one thread (a frame already uses
    every core)."""

    def __init__(self):
        self._queue = collections.deque()
        self._lock = threading.Lock()
        self._thread = None
        self.jobs = []

    def submit(self, job):
        with self._lock:
            self.jobs.append(job)
            self._queue.append(job)
            if self._thread is None or not self._thread.is_alive():
                self._thread = threading.Thread(target=self._work, name="aureole", daemon=True)
                self._thread.start()

    def _work(self):
        while True:
            with self._lock:
                if not self._queue:
                    self._thread = None
                    return
                job = self._queue.popleft()
            job.run()

    def busy(self):
        return any(not job.finished for job in self.jobs)

    def cancel_all(self):
        for job in self.jobs:
            job.cancel.set()

    def wait(self, timeout=None):
        thread = self._thread
        if thread is not None:
            thread.join(timeout)

    def trim(self, keep):
        """Forgets the oldest reported jobs beyond the last `keep`, so that
        a long session does not hold every frame it ever applied."""
        with self._lock:
            old = [job for job in self.jobs if job.reported][:-keep or None]
            self.jobs = [job for job in self.jobs if job not in old]
