"""Progress lines of a long identification, with an estimate of the time left, on stderr.

A method counts its work in units of its own (samples pushed through the network, population
members simulated) and reports ``update(done, message)``; the estimate is the elapsed time
scaled by the work still to do, capped by the method's time budget. Early stopping can end a
method sooner than estimated, never later than the budget.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable

ProgressSpec = bool | Callable[[str], None]


class Progress:
    """Throttled progress lines ``[label  12.3 s, ~8 s left] message``.

    Parameters
    ----------
    label : str
        Prefix naming the method (``"nn"``, ``"boucwen"``).
    total_work : float
        Work units of the whole method (0: no estimate).
    spec : bool or callable
        True prints to ``sys.stderr``, False prints nothing, a callable receives each line.
    every_s : float
        Least time between two lines (``force=True`` lines always print).
    budget_s : float, optional
        The method stops at this wall time at the latest; caps the estimate.
    upper_bound : bool
        Early stopping can skip part of the work: the estimate is shown as a bound ("<= 40 s
        left") rather than a guess ("~40 s left").
    """

    def __init__(
        self,
        label: str,
        total_work: float,
        spec: ProgressSpec = True,
        every_s: float = 3.0,
        budget_s: float | None = None,
        upper_bound: bool = False,
    ) -> None:
        self.label = label
        self.total_work = float(total_work)
        self.spec = spec
        self.every_s = float(every_s)
        self.budget_s = budget_s
        self.upper_bound = upper_bound
        self.t0 = time.perf_counter()
        self.last = self.t0
        self.done = 0.0

    def elapsed(self) -> float:
        return time.perf_counter() - self.t0

    def left_s(self) -> float | None:
        """Estimated seconds left, or None before any work is done."""
        elapsed = self.elapsed()
        if self.total_work <= 0 or self.done < 0.01 * self.total_work:
            return None  # too little done to say
        left = elapsed * max(0.0, self.total_work - self.done) / self.done
        if self.budget_s is not None:
            left = min(left, max(0.0, self.budget_s - elapsed))
        return left

    def update(self, done: float | None, message: str, force: bool = False) -> None:
        if done is not None:
            self.done = float(done)
        if not self.spec:
            return
        now = time.perf_counter()
        if not force and now - self.last < self.every_s:
            return
        self.last = now
        left = self.left_s()
        eta = ""
        if left is not None and self.done < self.total_work:
            eta = f", {'<=' if self.upper_bound else '~'}{left:.0f} s left"
        line = f"[{self.label} {now - self.t0:6.1f} s{eta}] {message}"
        if callable(self.spec):
            self.spec(line)
        else:
            print(line, file=sys.stderr, flush=True)
