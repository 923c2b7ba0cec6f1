"""Progress of ``linecheck scan``, driven by :func:`linecheck.batch.run_scan`'s
``progress("scan", done, total)`` callback.

In a terminal: one bar (positions done / total, elapsed time, time left).  Piped (CI, a log
file), where a bar draws nothing: a first line naming the scan and where it runs, then a
``progress:`` line whenever more positions are done, at most every ``interval`` seconds -- a
100,000-position scan is never silent for minutes.
"""

from __future__ import annotations

import time
from typing import Any

from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from .common import err_console


def _clock(seconds: float) -> str:
    s = int(round(max(0.0, seconds)))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


class ScanDisplay:
    """Callable ``display(stage, done, total)`` for a scan; a context manager around it."""

    def __init__(self, description: str, *, interval: float = 5.0, live: bool | None = None,
                 console: Any = None) -> None:
        self.console = console if console is not None else err_console
        self.live = self.console.is_terminal if live is None else live
        self.description = description
        self.interval = interval
        self.t0 = time.monotonic()
        self.last_line = float("-inf")
        self.last_done = 0
        self.started = False
        self.bars = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                             TimeRemainingColumn(), console=self.console, transient=True, disable=not self.live)
        self.task: Any = None

    def __enter__(self) -> ScanDisplay:
        self.bars.__enter__()
        return self

    def __exit__(self, *exc: object) -> None:
        self.bars.__exit__(*exc)

    def _line(self, text: str) -> None:
        self.console.print(text, highlight=False, soft_wrap=True, markup=False, emoji=False)
        self.last_line = time.monotonic()

    def line(self, done: int, total: int) -> str:
        """``positions 2500/100000 (2 %), elapsed 0:01:00, ETA 0:39:00``."""
        elapsed = time.monotonic() - self.t0
        pct = 100.0 * done / total if total else 100.0
        eta = _clock(elapsed * (total - done) / done) if done else "--:--:--"
        return f"positions {done}/{total} ({pct:.0f} %), elapsed {_clock(elapsed)}, ETA {eta}"

    def __call__(self, stage: str, done: int, total: int) -> None:
        if not self.started:
            self.started, self.t0 = True, time.monotonic()
            if self.live:
                self.task = self.bars.add_task(self.description, total=max(total, 1))
            else:
                self._line(f"{self.description}: {total} position(s)")
        if self.live:
            self.bars.update(self.task, completed=done, total=max(total, 1))
        elif done > self.last_done and time.monotonic() - self.last_line >= self.interval:
            self.last_done = done
            self._line(f"progress: {self.line(done, total)}")
