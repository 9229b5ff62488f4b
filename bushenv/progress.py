"""Progress of long commands: lines on stderr with the share done and the time left.

Every command that runs longer than a few seconds reports through one ``Progress``: ``say``
prints a line (unless quiet), ``update(done, msg)`` prints at most every ``every_s`` seconds
with an estimate of the time left from the rate so far (work is counted in units the command
chooses: model evaluations, samples, training iterations). Results go to stdout, never here.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import TextIO


def format_seconds(s: float) -> str:
    """``75`` -> ``"1 min 15 s"``; ``8.2`` -> ``"8 s"``."""
    s = max(0.0, float(s))
    if s < 60:
        return f"{s:.0f} s"
    if s < 3600:
        return f"{int(s // 60)} min {int(s % 60):02d} s"
    return f"{int(s // 3600)} h {int(s % 3600 // 60):02d} min"


class Progress:
    """Progress lines on ``stream`` (stderr) for ``total`` units of work.

    Parameters
    ----------
    total : float, optional
        Units of work the command will do; without it no time left is estimated.
    quiet : bool
        Print nothing (``--quiet``).
    every_s : float
        Least time between two ``update`` lines.
    sink : callable, optional
        Receives each line instead of ``stream`` (tests, or a caller's own log).
    """

    def __init__(
        self,
        total: float | None = None,
        quiet: bool = False,
        every_s: float = 2.0,
        stream: TextIO | None = None,
        sink: Callable[[str], None] | None = None,
    ) -> None:
        self.total = total
        self.quiet = quiet
        self.every_s = every_s
        self.stream = stream
        self.sink = sink
        self.t0 = time.perf_counter()
        self.done = 0.0
        self._last = -float("inf")

    def elapsed_s(self) -> float:
        return time.perf_counter() - self.t0

    def left_s(self) -> float | None:
        """Estimated seconds left, or None before any work is done or without a total."""
        if not self.total or self.done <= 0:
            return None
        rate = self.done / max(self.elapsed_s(), 1e-9)
        return max(0.0, self.total - self.done) / rate

    def say(self, msg: str) -> None:
        """One line now (unless quiet), prefixed with the time elapsed."""
        if self.quiet:
            return
        if self.sink is not None:
            self.sink(msg)
            return
        stream = self.stream or sys.stderr
        print(f"[{format_seconds(self.elapsed_s()):>10}] {msg}", file=stream, flush=True)

    def update(self, done: float, msg: str = "", force: bool = False) -> None:
        """Work done so far is ``done`` units; a line with the time left, throttled."""
        self.done = float(done)
        now = time.perf_counter()
        if not (force or now - self._last >= self.every_s):
            return
        self._last = now
        left = self.left_s()
        share = f"{100 * self.done / self.total:.0f} %" if self.total else ""
        eta = f", about {format_seconds(left)} left" if left is not None else ""
        tail = f" ({share}{eta})" if share or eta else ""
        self.say(f"{msg}{tail}")

    def __call__(self, msg: str) -> None:
        self.say(msg)
