"""Records ready for fitting, and their regressor columns with the Gram products, cached.

A fit of a candidate on a set of records needs, per record, ``A^T A``, ``A^T y`` and
``y^T y`` of its columns ``A`` (a spring/damper block plus one block per effect and shape) and
the measured force ``y`` (advanced by the candidate's delay, minus a non-linear baseline).
They are summed over the records fitted on, so leaving one record out costs a subtraction,
not a new pass over the data; each block product is computed once.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, field
from itertools import count
from typing import Any

import numpy as np
from scipy import signal

from bushenv.diagnose.candidates import get_effect
from bushenv.diagnose.effects.base import Scales, Signals
from bushenv.diagnose.effects.timeshift import shift_columns

_UIDS = count()
SPRING = ("spring", "x,v")  # the linear spring and damper block (or the baseline's correction)
DAMPER = ("spring", "v")  # the damper alone, when a backbone replaces the spring

Block = tuple[str, Any]
EDGE_FACTOR = 2.0  # the low-pass edge over the top of the displacement's signal band
TARGETS_KEPT = 256  # force targets (one per record and delay) kept
COLUMNS_KEPT_BYTES = 512 * 2**20  # columns kept, least recently used out (a refined leak
# visits many shapes once)


@dataclass
class Prepared:
    """One record ready for fitting: signals, measured force, baseline force ``b0``.

    ``role`` is ``"train"`` or ``"test"``; ``band_edge_hz`` the low-pass edge applied to the
    displacement before differentiating, when it has a noise floor (else None).
    """

    name: str
    role: str
    time: np.ndarray
    signals: Signals
    force: np.ndarray
    b0: np.ndarray
    band_edge_hz: float | None = None
    uid: int = field(default_factory=lambda: next(_UIDS))
    start_of: int | None = None  # the uid of its session's first record (they share a start)

    @property
    def start_key(self) -> int:
        """Whose per-record block (a warm start) this record's is: its session's, else its own."""
        return self.uid if self.start_of is None else self.start_of

    @property
    def dt(self) -> float:
        return self.signals.dt

    @property
    def n(self) -> int:
        return int(self.force.size)


def whole_record_psd(x: np.ndarray, dt: float, nper: int) -> tuple[np.ndarray, np.ndarray]:
    """(f, PSD) averaged over Hann-windowed segments spread evenly from the first sample to the
    last, so every sample counts and the record read backwards gives the same estimate.

    (scipy's Welch steps by half a segment and drops what is left at the end: up to a third
    of a record, the top of a sweep that runs low to high.)
    """
    nper = int(min(nper, x.size))
    count_ = max(int(np.ceil(2 * x.size / nper)) - 1, 1)
    starts = np.unique(np.round(np.linspace(0, x.size - nper, count_)).astype(int))
    win = signal.get_window("hann", nper)
    segs = np.stack([x[s : s + nper] for s in starts])
    segs = (segs - segs.mean(axis=1, keepdims=True)) * win
    p = np.mean(np.abs(np.fft.rfft(segs, axis=1)) ** 2, axis=0) * 2 * dt / np.sum(win * win)
    return np.fft.rfftfreq(nper, dt), p


def noise_band_edge(x: np.ndarray, dt: float) -> float | None:
    """Upper edge (Hz) of a displacement's signal band when a noise floor lies above it.

    The PSD is taken over the whole record (``whole_record_psd``, independent of sample
    order). The floor is its median over the top fifth of the band; the edge is the highest
    frequency 10 dB above it, times ``EDGE_FACTOR``. None when there is no clear floor (less
    than 40 dB below the peak) or the edge is within 80 % of Nyquist: then there is nothing
    to filter away.
    """
    if x.size < 64:
        return None
    f, p = whole_record_psd(x, dt, 4096)
    floor = float(np.median(p[f >= 0.8 * f[-1]]))
    if not (floor > 0 and floor < 1e-4 * p.max()):
        return None
    # twice the top of the signal band: the 4th-order zero-phase filter then leaves the band
    # within 0.5 % (at 1.2x it took 12 % off the band's top and made a phase-free bushing
    # look delayed)
    edge = EDGE_FACTOR * float(f[np.nonzero(p >= 10.0 * floor)[0][-1]])
    return edge if edge < 0.8 * f[-1] else None


def smoothed_displacement(x: np.ndarray, dt: float) -> tuple[np.ndarray, float | None]:
    """(x, None), or x low-passed (zero phase) below its noise floor and the edge (Hz).

    A measured displacement's noise, twice differentiated, swamps the acceleration: it biases
    a fitted mass toward zero (errors in variables) and turns every prediction that uses the
    acceleration into noise. Every column is computed from the smoothed displacement.
    """
    edge = noise_band_edge(x, dt)
    if edge is None:
        return x, None
    return signal.sosfiltfilt(signal.butter(4, edge, fs=1.0 / dt, output="sos"), x), edge


class ColumnStore:
    """Columns of every (record, block), and their products, computed once.

    ``admissible``: the spring and damper are the specimen's own (the linear baseline), so
    their weights are bounded at 0 -- no passive bushing has a negative stiffness or damping
    (a force-channel lag fitted as a mass and a negative damper is not an answer). With a
    non-linear baseline they are corrections to it, of either sign.
    """

    def __init__(self, scales: Scales, admissible: bool = True) -> None:
        self.scales = scales
        self.admissible = admissible
        self._cols: OrderedDict[tuple, np.ndarray] = OrderedDict()
        self._cols_bytes = 0
        self._gram: dict[tuple, np.ndarray] = {}
        self._rhs: dict[tuple, np.ndarray] = {}
        self._targets: OrderedDict[tuple, tuple[np.ndarray, float]] = OrderedDict()

    def columns(self, prep: Prepared, block: Block) -> np.ndarray:
        key = (prep.uid, block)
        if key in self._cols:
            self._cols.move_to_end(key)
            return self._cols[key]
        if block == SPRING:
            cols = np.stack([prep.signals.x, prep.signals.v], axis=1)
        elif block == DAMPER:
            cols = prep.signals.v[:, None].copy()
        else:
            cols = get_effect(block[0]).block_columns(prep.signals, block[1], self.scales)
        cols = np.ascontiguousarray(cols)
        while self._cols and self._cols_bytes + cols.nbytes > COLUMNS_KEPT_BYTES:
            self._cols_bytes -= self._cols.popitem(last=False)[1].nbytes
        self._cols[key] = cols
        self._cols_bytes += cols.nbytes
        return cols

    def design(self, prep: Prepared, blocks: tuple[Block, ...]):
        """(T, p) columns of ``blocks`` side by side."""
        return np.concatenate([self.columns(prep, b) for b in blocks], axis=1)

    def gram(self, prep: Prepared, blocks: tuple[Block, ...]) -> np.ndarray:
        """A^T A of the design, (p, p)."""
        rows = []
        for b1 in blocks:
            row = []
            for b2 in blocks:
                key = (prep.uid, b1, b2)
                if key not in self._gram:
                    tkey = (prep.uid, b2, b1)
                    if tkey in self._gram:
                        self._gram[key] = self._gram[tkey].T
                    else:
                        self._gram[key] = self.columns(prep, b1).T @ self.columns(prep, b2)
                row.append(self._gram[key])
            rows.append(np.concatenate(row, axis=1))
        return np.concatenate(rows, axis=0)

    def target(self, prep: Prepared, delay_s: float) -> tuple[np.ndarray, float]:
        """(y, y^T y): the force advanced by the delay, minus b0."""
        key = (prep.uid, delay_s)
        if key not in self._targets:
            if len(self._targets) >= TARGETS_KEPT:  # a delay search visits many values once
                self._targets.popitem(last=False)
            y = shift_columns(prep.force, -delay_s, prep.dt) - prep.b0
            self._targets[key] = (y, float(y @ y))
        return self._targets[key]

    def rhs(self, prep: Prepared, blocks: tuple[Block, ...], delay_s: float):
        """(A^T y (p,), y^T y) for the target at ``delay_s``."""
        parts = []
        for b in blocks:
            key = (prep.uid, b, delay_s)
            if key not in self._rhs:
                y = self.target(prep, delay_s)[0]
                self._rhs[key] = self.columns(prep, b).T @ y
            parts.append(self._rhs[key])
        return np.concatenate(parts), self.target(prep, delay_s)[1]

    def columns_count(self, block: Block) -> int:
        if block[0] == "spring":
            return len(block[1].split(","))
        return get_effect(block[0]).columns_count(block[1], self.scales)

    def lower(self, blocks: tuple[Block, ...]) -> np.ndarray:
        """Lower bounds of the weights: spring and damper >= 0 when ``admissible`` (else free),
        the effects' own bounds."""
        out = []
        for b in blocks:
            if b[0] == "spring":
                out.append(np.full(len(b[1].split(",")), 0.0 if self.admissible else -np.inf))
            else:
                out.append(get_effect(b[0]).block_lower(b[1], self.scales))
        return np.concatenate(out)

    def clear(self) -> None:
        self._cols.clear()
        self._cols_bytes = 0
        self._gram.clear()
        self._rhs.clear()
        self._targets.clear()
