"""A study's progress: a bar on a terminal, else a line every tenth of the points or every 10 s
(under nohup or a redirect too), with what failed, the rate of ok points per worker present, and
the time left."""

from __future__ import annotations

import sys
import time as clock

EVERY_SECONDS = 10.0


class Progress:
    def __init__(self, total: int, stream=None, terminal=None, every_seconds=EVERY_SECONDS):
        self.stream = stream or sys.stderr
        self.total = total
        self.done = self.failed = self.ok = 0
        self.started = self._shown = clock.monotonic()
        self.every_points = max(1, total // 10)
        self.every_seconds = every_seconds
        self._shown_at = 0
        self._workers = []  # the workers present, sampled as the study goes
        terminal = self.stream.isatty() if terminal is None else terminal
        self.bar = None
        if terminal:
            from tqdm import tqdm

            self.bar = tqdm(total=total, unit="point", desc="sweep", leave=False, file=self.stream)

    def workers(self, n: int):
        self._workers.append(n)

    @property
    def mean_workers(self) -> float:
        return sum(self._workers) / len(self._workers) if self._workers else 0.0

    def point(self, status: str):
        self.done += 1
        self.failed += status.startswith("failed")
        self.ok += not status.startswith("failed")
        if self.bar is not None:
            self.bar.update(1)
            self.bar.set_postfix(failed=self.failed, refresh=False)
        elif self.done - self._shown_at >= self.every_points:
            self.show()

    def tick(self):
        """Called about every second: a line if 10 s went by without one."""
        if self.bar is None and clock.monotonic() - self._shown >= self.every_seconds:
            self.show()

    def show(self):
        now = clock.monotonic()
        wall = now - self.started
        rate = self.ok / wall / max(self.mean_workers, 1) if wall > 0 else 0.0
        left = (self.total - self.done) * wall / self.done if self.done else float("nan")
        print(f"sweep: {self.done}/{self.total} points, {self.failed} failed, {rate:.3g} ok points/s per worker "
              f"({self.mean_workers:.3g} workers), {wall:.0f} s gone, about {left:.0f} s left", file=self.stream, flush=True)
        self._shown, self._shown_at = now, self.done

    def say(self, text: str):
        if self.bar is not None:
            self.bar.write(text, file=self.stream)
        else:
            print(text, file=self.stream, flush=True)

    def close(self):
        if self.bar is not None:
            self.bar.close()
