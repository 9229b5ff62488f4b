"""Progress of long commands: lines on stderr with the share done and the time left.

Every command or method that runs longer than a few seconds reports through one ``Progress``:
``say`` prints a line (unless quiet), ``update(done, msg)`` prints at most every ``every_s``
seconds with an estimate of the time left from the rate so far (work is counted in units the
caller chooses: model evaluations, samples, population members), capped by a time budget when
the work has one; where early stopping can skip work the estimate is shown as a bound.
Results go to stdout, never here.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import TextIO

ProgressSpec = bool | Callable[[str], None]  # print to stderr, be silent, or hand lines over


def format_seconds(s: float) -> str:
    """``75`` -> ``"1 min 15 s"``; ``8.2`` -> ``"8 s"``."""
    s = max(0.0, float(s))
    if s < 60:
        return f"{s:.0f} s"
    if s < 3600:
        return f"{int(s // 60)} min {int(s % 60):02d} s"
    return f"{int(s // 3600)} h {int(s % 3600 // 60):02d} min"


class Progress:
    """Progress lines for ``total`` units of work.

    Parameters
    ----------
    total : float, optional
        Units of work to do; without it no time left is estimated.
    quiet : bool
        Print nothing (``--quiet``).
    every_s : float
        Least time between two ``update`` lines (``force=True`` lines always print).
    stream : file, optional
        Where lines go (default ``sys.stderr``).
    sink : callable, optional
        Receives each line instead of ``stream`` (tests, or a caller's own log).
    label : str
        Names the work in every line (``"nn"``, ``"boucwen"``).
    budget_s : float, optional
        The work stops at this wall time at the latest: caps the estimate.
    upper_bound : bool
        Early stopping can skip work: the estimate is a bound ("<= 40 s left").
    """

    def __init__(
        self,
        total: float | None = None,
        quiet: bool = False,
        every_s: float = 2.0,
        stream: TextIO | None = None,
        sink: Callable[[str], None] | None = None,
        label: str = "",
        budget_s: float | None = None,
        upper_bound: bool = False,
    ) -> None:
        self.total, self.quiet, self.every_s = total, quiet, every_s
        self.stream, self.sink, self.label = stream, sink, label
        self.budget_s, self.upper_bound = budget_s, upper_bound
        self.t0 = time.perf_counter()
        self.done = 0.0
        self._last = self.t0  # the first throttled line comes after every_s

    @classmethod
    def of(cls, spec: ProgressSpec, **kwargs) -> Progress:
        """From a ``ProgressSpec``: True prints to stderr, False is quiet, a callable receives."""
        if callable(spec):
            return cls(sink=spec, **kwargs)
        return cls(quiet=not spec, **kwargs)

    def elapsed_s(self) -> float:
        return time.perf_counter() - self.t0

    def left_s(self) -> float | None:
        """Estimated seconds left; None without a total, before 1 % of it, or once done."""
        if not self.total or self.done < 0.01 * self.total or self.done >= self.total:
            return None
        elapsed = self.elapsed_s()
        left = elapsed * (self.total - self.done) / self.done
        if self.budget_s is not None:
            left = min(left, max(0.0, self.budget_s - elapsed))
        return left

    def _emit(self, line: str) -> None:
        if self.quiet:
            return
        if self.sink is not None:
            self.sink(line)
            return
        print(line, file=self.stream or sys.stderr, flush=True)

    def _prefix(self, eta: str = "") -> str:
        label = f"{self.label} " if self.label else ""
        return f"[{label}{self.elapsed_s():6.1f} s{eta}]"

    def say(self, msg: str) -> None:
        """One line now (unless quiet), prefixed with the label and the time elapsed."""
        self._emit(f"{self._prefix()} {msg}")

    def update(self, done: float | None, msg: str = "", force: bool = False) -> None:
        """Work done so far is ``done`` units (None: unchanged); a line with the share done
        and the time left, at most every ``every_s`` seconds unless ``force``."""
        if done is not None:
            self.done = float(done)
        now = time.perf_counter()
        if not (force or now - self._last >= self.every_s):
            return
        self._last = now
        left = self.left_s()
        eta = ""
        if left is not None:
            eta = f", {'<=' if self.upper_bound else '~'}{format_seconds(left)} left"
        share = f" ({100 * self.done / self.total:.0f} %)" if self.total else ""
        self._emit(f"{self._prefix(eta)} {msg}{share}")

    def __call__(self, msg: str) -> None:
        self.say(msg)
