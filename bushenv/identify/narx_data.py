"""The NARX training problem: records scaled, padded and split, as the training stages index them.

Each record r is split into a training part (the first 1 - ``val_fraction``) and a validation
part (the rest). Its scaled displacement and target (the force, or for the hybrid the residual
F - k x - c v) are stored end to end in ``xs_p`` / ``ys_p``, each record preceded by ``pad``
samples at rest, so the lagged inputs of a record's first samples are its own rest history and
never another record's samples. Indices below are positions in those padded arrays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from bushenv.identify.data import IdentificationError, TrainingSet
from bushenv.identify.linear import least_squares_kc
from bushenv.identify.narx_torch import x_windows, y_history
from bushenv.models.narx import scaling_of

VAL_MIN_SAMPLES = 10  # a validation part shorter than this says nothing
SAMPLES_PER_LAG = 10  # a training part must hold 10 samples per lag (plus the current one)


@dataclass
class NarxProblem:
    """Scaled, padded records of one NARX identification.

    Attributes
    ----------
    kind : {"nn", "hybrid"}
    n_past_x, n_past_f, pad : int
        Lags and the rest padding before each record (max of the lags).
    xs_p, ys_p : (N,) float64
        Scaled displacement and target of every record, each after ``pad`` rest samples.
    train, val : list of (lo, hi)
        Per record, the prediction indices [lo, hi) of its training / validation part.
    x_off, x_sc, f_off, f_sc : float
        Scaling, m and N: xs = (x - x_off) / x_sc, ys = (target - f_off) / f_sc, set to
        [-1, 1] over the training parts of all records (seed 000 §4.2).
    k, c : float
        Hybrid backbone, N/m and N s/m (least squares on the training parts); 0 for "nn".
    f_val, backbone_val : (V,) float64
        Measured force and backbone force on the validation parts, end to end.
    data : TrainingSet
        The records themselves (for loss terms that need physical values).
    """

    kind: str
    n_past_x: int
    n_past_f: int
    pad: int
    xs_p: np.ndarray
    ys_p: np.ndarray
    train: list[tuple[int, int]]
    val: list[tuple[int, int]]
    x_off: float
    x_sc: float
    f_off: float
    f_sc: float
    k: float
    c: float
    f_val: np.ndarray
    backbone_val: np.ndarray
    data: TrainingSet

    @property
    def dt(self) -> float:
        return self.data.dt

    @property
    def n_train(self) -> int:
        return sum(hi - lo for lo, hi in self.train)

    @property
    def longest_train(self) -> int:
        return max(hi - lo for lo, hi in self.train)

    def one_step_batch(self, ranges: list[tuple[int, int]]) -> tuple[torch.Tensor, torch.Tensor]:
        """Teacher-forcing inputs (N, 1 + nx + nf) with MEASURED past outputs, and targets (N,),
        for every prediction index in ``ranges``."""
        starts = np.concatenate([np.arange(lo, hi) for lo, hi in ranges])
        inp = np.concatenate(
            [
                x_windows(self.xs_p, starts, 1, self.n_past_x)[:, 0, :],
                y_history(self.ys_p, starts, self.n_past_f),
            ],
            axis=1,
        )
        return torch.from_numpy(inp), torch.from_numpy(self.ys_p[starts])

    def window_starts(self, length: int) -> np.ndarray:
        """Every start of a ``length``-sample window inside one record's training part."""
        parts = [np.arange(lo, hi - length + 1) for lo, hi in self.train if hi - lo >= length]
        return np.concatenate(parts) if parts else np.zeros(0, dtype=np.int64)

    def windows(
        self, starts: np.ndarray, length: int
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Free-run inputs of windows: x (W, L, 1 + nx), measured history (W, nf), target (W, L)."""
        x_in = x_windows(self.xs_p, starts, length, self.n_past_x)
        y_hist = y_history(self.ys_p, starts, self.n_past_f)
        tgt = self.ys_p[starts[:, None] + np.arange(length)[None, :]]
        return torch.from_numpy(x_in), torch.from_numpy(y_hist), torch.from_numpy(tgt)

    def validation_runs(self) -> list[tuple[torch.Tensor, torch.Tensor]]:
        """Per record, its validation part as one free-run window from the measured history."""
        runs = []
        for lo, hi in self.val:
            s = np.array([lo])
            x_in = x_windows(self.xs_p, s, hi - lo, self.n_past_x)
            runs.append(
                (torch.from_numpy(x_in), torch.from_numpy(y_history(self.ys_p, s, self.n_past_f)))
            )
        return runs


def _split(data: TrainingSet, val_fraction: float, lag: int) -> list[int]:
    """Training-part length of each record; refuses records too short for the split or lags."""
    need = SAMPLES_PER_LAG * (1 + lag)
    lengths = []
    for seg in data.segments:
        T = len(seg)
        t_train = int(round(T * (1.0 - val_fraction)))
        if T - t_train < VAL_MIN_SAMPLES:
            raise IdentificationError(
                f"{seg.label}: record of {T} samples too short for a {val_fraction:.0%} "
                f"validation split of at least {VAL_MIN_SAMPLES} samples"
            )
        if t_train < need:
            raise IdentificationError(
                f"{seg.label}: record too short for the lags: its training part holds "
                f"{t_train} samples ({1 - val_fraction:.0%} of {T}), a largest lag of {lag} "
                f"needs at least {need} ({SAMPLES_PER_LAG} per lag and current sample); use a "
                "longer record or smaller --n-past-x / --n-past-f"
            )
        lengths.append(t_train)
    return lengths


def narx_problem(
    kind: str, data: TrainingSet, n_past_x: int, n_past_f: int, val_fraction: float
) -> NarxProblem:
    """Split, scale and pad ``data`` for a NARX identification (see the module docstring)."""
    nx, nf = int(n_past_x), int(n_past_f)
    pad = max(nx, nf)
    t_train = _split(data, val_fraction, pad)
    segs = data.segments
    k = c = 0.0
    if kind == "hybrid":
        k, c = least_squares_kc(
            *(
                np.concatenate([getattr(s, a)[:n] for s, n in zip(segs, t_train, strict=True)])
                for a in "xfv"
            )
        )
    targets = [s.f - (k * s.x + c * s.v) for s in segs]
    x_tr = np.concatenate([s.x[:n] for s, n in zip(segs, t_train, strict=True)])
    y_tr = np.concatenate([y[:n] for y, n in zip(targets, t_train, strict=True)])
    x_off, x_sc = scaling_of(x_tr.min(), x_tr.max())
    f_off, f_sc = scaling_of(y_tr.min(), y_tr.max())
    xs_parts, ys_parts, train, val = [], [], [], []
    at = 0
    for seg, y, n in zip(segs, targets, t_train, strict=True):
        xs_parts += [np.full(pad, (0.0 - x_off) / x_sc), (seg.x - x_off) / x_sc]
        ys_parts += [np.full(pad, (0.0 - f_off) / f_sc), (y - f_off) / f_sc]
        train.append((at + pad, at + pad + n))
        val.append((at + pad + n, at + pad + len(seg)))
        at += pad + len(seg)
    return NarxProblem(
        kind=kind,
        n_past_x=nx,
        n_past_f=nf,
        pad=pad,
        xs_p=np.concatenate(xs_parts),
        ys_p=np.concatenate(ys_parts),
        train=train,
        val=val,
        x_off=x_off,
        x_sc=x_sc,
        f_off=f_off,
        f_sc=f_sc,
        k=k,
        c=c,
        f_val=np.concatenate([s.f[n:] for s, n in zip(segs, t_train, strict=True)]),
        backbone_val=np.concatenate(
            [k * s.x[n:] + c * s.v[n:] for s, n in zip(segs, t_train, strict=True)]
        ),
        data=data,
    )
