"""A study's FMUs on the workers: a worker plugin per study, not scattered data.

Dask keeps a registered plugin on the scheduler and gives it to every worker, those that join
later included, so a cluster that lost every worker gets the FMUs again from the first new one.
Each study names its plugin uniquely (`study_name`): its release (unregistering the plugin at its
end) cannot drop another study's copy, even of the very same FMU, as a release of a shared
scattered key could (docs/studies.md). On a worker the plugin writes its files into a folder of
its own only when a task asks for it, and removes the folder, and closes what was made from it
(`on_teardown`), when the study ends or the worker closes.
"""

from __future__ import annotations

import shutil
import tempfile
import uuid
from pathlib import Path

from distributed import WorkerPlugin


def study_name(what: str) -> str:
    """A plugin name no other study has."""
    return f"webline-{what}-{uuid.uuid4().hex}"


class StudyFiles(WorkerPlugin):
    """Files (name -> bytes) a study's tasks need, on every worker."""

    idempotent = False

    def __init__(self, name: str, files: dict):
        self.name = name
        self.files = files
        self._folder = None
        self._teardowns = []

    def setup(self, worker):
        self._folder = None
        self._teardowns = []

    def folder(self) -> Path:
        """The files written into a folder of this worker (once)."""
        if self._folder is None:
            folder = Path(tempfile.mkdtemp(prefix="webline-study-"))
            for n, data in self.files.items():
                (folder / n).write_bytes(data)
            self._folder = folder
        return self._folder

    def on_teardown(self, close):
        """`close()` runs when the study ends on this worker (before its folder goes)."""
        self._teardowns.append(close)

    def teardown(self, worker):
        try:
            for close in self._teardowns:
                close()
        finally:
            if self._folder is not None:
                shutil.rmtree(self._folder, ignore_errors=True)


def study_files(name: str) -> StudyFiles:
    """This worker's copy of a study's files (inside a task)."""
    from distributed import get_worker

    return get_worker().plugins[name]
