"""A study's rows kept as they arrive, so that an interrupted or killed study can be resumed.

Beside the table (`out/sweep.csv`) a folder `out/sweep.partial/` holds:

- `study.json`: what the study is (a digest of the scene's text, the engine, the seed, a digest of
  the design, the step, whether series are kept, the user's metrics); `--resume` refuses a folder
  made by another study, naming what differs;
- `rows.jsonl`: one line per finished point, appended and flushed as it arrives: its index, its row
  (JSON keeps floats exactly and dicts in order, so a row read back is the row written) and its
  times, which stay out of the table;
- `series/NNNNNNNN.npy`: a point's recorded signals (time first), written whole and renamed into
  place before its line, so a line in the journal always has its series.

A killed process loses only the points in flight (a torn last line is ignored). The folder is
removed once the study has every point ok; else it stays for `--resume`.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np


class StudyError(Exception):
    """A study that cannot start or resume (a scheduler that cannot be used, a journal of another
    study): why, in one line."""


def folder_of(table) -> Path:
    table = Path(table)
    return table.with_name(f"{table.stem}.partial")


def identity(scene_path, engine, design, step, series, metrics) -> dict:
    """What makes two runs the same study, in the order a difference is named."""
    scene = hashlib.sha256(Path(scene_path).read_bytes()).hexdigest()
    points = hashlib.sha256(json.dumps(design.points, sort_keys=True).encode()).hexdigest()
    return {"scene": scene, "engine": engine, "seed": design.seed, "design": points, "points": len(design.points),
            "step": step, "series": bool(series), "metrics": list(metrics)}


WHAT_DIFFERS = {"scene": "the scene's text", "engine": "the engine", "seed": "the seed", "design": "the design (--grid, --sample, --n)",
                "points": "the number of points", "step": "the step", "series": "whether series are kept (--series, --plot)",
                "metrics": "the metrics (--metric)"}


@dataclass
class Done:
    """A finished point as the journal keeps it."""

    row: dict
    times: list  # [started, ended, simulation] on its worker


class Journal:
    def __init__(self, folder: Path, study: dict):
        self.folder = Path(folder)
        self.study = study
        self.series = self.folder / "series"
        self._rows = None

    @classmethod
    def start(cls, table, study: dict, resume: bool) -> tuple["Journal", dict]:
        """The journal of this study and the points it already has ({index: Done}). Without
        `resume`, a folder already there is refused (it holds an unfinished study's points)."""
        folder = folder_of(table)
        journal = cls(folder, study)
        if folder.exists() and not resume:
            raise StudyError(f"{folder} holds the points of an unfinished study: give --resume to finish it, "
                               "or remove the folder to start again")
        if not folder.exists():  # made with the first finished point: a study refused or stopped before has none
            if resume:
                raise StudyError(f"--resume: there is no unfinished study at {folder} (the table {table} is complete "
                               "or was never started)")
            return journal, {}
        journal.check(json.loads((folder / "study.json").read_text()))
        return journal, journal.read()

    @staticmethod
    def seed_of(table):
        """The seed an unfinished study at `table` drew (for --resume without --seed), or None."""
        try:
            return json.loads((folder_of(table) / "study.json").read_text()).get("seed")
        except (OSError, ValueError):
            return None

    def check(self, before: dict):
        for key, what in WHAT_DIFFERS.items():
            if before.get(key) != self.study.get(key):
                shown = "" if key in ("scene", "design") else f" ({before.get(key)!r}, now {self.study.get(key)!r})"
                raise StudyError(f"--resume: {self.folder} is another study's: {what} differs{shown}")

    def read(self) -> dict:
        done = {}
        path = self.folder / "rows.jsonl"
        if path.exists():
            for line in path.read_text().splitlines():
                try:
                    entry = json.loads(line)
                except ValueError:  # the line a kill tore: its point runs again
                    continue
                done[entry["point"]] = Done(entry["row"], entry["times"])
        return done

    def add(self, index: int, row: dict, times, time=None, data=None):
        if not self.folder.exists():
            self.series.mkdir(parents=True)
            (self.folder / "study.json").write_text(json.dumps(self.study, indent=1) + "\n")
        if time is not None and data is not None:
            path = self.series / f"{index:08d}.npy"
            tmp = path.with_suffix(".tmp")
            with open(tmp, "wb") as f:
                np.save(f, np.column_stack([time, data]))
            os.replace(tmp, path)
        if self._rows is None:
            path = self.folder / "rows.jsonl"
            torn = path.exists() and path.stat().st_size and not path.read_bytes().endswith(b"\n")
            self._rows = open(path, "a")
            if torn:  # a kill tore the last line: the next one starts on a line of its own
                self._rows.write("\n")
        self._rows.write(json.dumps({"point": index, "row": row, "times": list(times)}) + "\n")
        self._rows.flush()

    def series_of(self, index: int):
        """(time, data) of a point, or None (a failed point has none)."""
        path = self.series / f"{index:08d}.npy"
        if not path.exists():
            return None
        x = np.load(path)
        return x[:, 0], x[:, 1:]

    def close(self):
        if self._rows is not None:
            self._rows.close()
            self._rows = None

    def remove(self):
        self.close()
        shutil.rmtree(self.folder, ignore_errors=True)
