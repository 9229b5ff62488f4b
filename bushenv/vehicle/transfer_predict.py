"""The predictor from component-level bushing errors to vehicle-level changes, and its check.

Superposition of measured responses: each component error j (pivot, coordinate, kind) was run
alone at the campaign's size +s_0 (and, for the second order, at -s_0), giving the difference
histories d_j+(t), d_j-(t) of every vehicle output against the reference car. For errors of
sizes s_j at once, a_j = s_j / s_0, the predicted difference is

    first order:   sum_j a_j d_j+(t)
    second order:  sum_j a_j (d_j+ - d_j-)(t) / 2 + a_j^2 (d_j+ + d_j-)(t) / 2

(each component's own curvature, from the two signs; no interaction terms). Either is a sum of
basis histories e_k(t) with weights w_k (a_j, then a_j^2), so its RMS over a manoeuvre is

    RMS(d_hat) = sqrt(w^T G w),   G_kl = mean_t sum_cols e_k(t) e_l(t)

(the cross terms keep two errors that cancel from adding up). ``TransferPredictor`` holds G per
manoeuvre and output, and the reference car's RMS of each output, so it predicts without a car;
``save``/``load`` write it as one ``.npz`` (plain arrays) with a JSON header.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import spearmanr

from bushenv.persist import atomic_write
from bushenv.vehicle.transfer_errors import ErrorTerm, TransferInputError

FORMAT = "bushenv-transfer-predictor"


@dataclass
class TransferPredictor:
    """``gram`` (M, O, J, J) per manoeuvre and output; ``baseline_rms`` (M, O) the reference
    car's RMS (SI; weighted a_w for the comfort outputs); ``components`` J (pivot, coord, kind);
    ``size_pct`` s_0; ``floors`` (O,) the RMS below which an output's relative change is not
    stated; ``order`` 1 (basis d_j+, K = J) or 2 (basis (d_j+ - d_j-)/2, then (d_j+ + d_j-)/2,
    K = 2 J)."""

    manoeuvres: tuple[str, ...]
    outputs: tuple[str, ...]
    components: tuple[tuple[str, str, str], ...]
    size_pct: float
    gram: np.ndarray
    baseline_rms: np.ndarray
    floors: np.ndarray
    order: int = 1

    def weights(self, terms: list[ErrorTerm]) -> np.ndarray:
        """(J,) s_j / s_0 of ``terms`` (each component at most once)."""
        index = {c: i for i, c in enumerate(self.components)}
        w = np.zeros(len(self.components))
        for t in terms:
            if t.component not in index:
                raise TransferInputError(f"error {t.label()}: not a component of this map")
            if w[index[t.component]] != 0:
                raise TransferInputError(f"error {'/'.join(t.component)} given twice")
            w[index[t.component]] = t.size_pct / self.size_pct
        return w

    def predict_rms(self, terms: list[ErrorTerm]) -> np.ndarray:
        """(M, O) predicted RMS change of each output in each manoeuvre, SI units."""
        a = self.weights(terms)
        w = a if self.order == 1 else np.concatenate([a, a * a])
        power = np.einsum("j,mojk,k->mo", w, self.gram, w)
        return np.sqrt(np.maximum(power, 0.0))

    def predict_pct(self, terms: list[ErrorTerm]) -> np.ndarray:
        """(M, O) predicted RMS change, % of the reference car's RMS; NaN where not stated."""
        return relative_pct(self.predict_rms(terms), self.baseline_rms, self.floors)

    def save(self, path: str | Path) -> None:
        header = {"format": FORMAT, "manoeuvres": list(self.manoeuvres),
                  "outputs": list(self.outputs), "components": [list(c) for c in self.components],
                  "size_pct": self.size_pct, "order": self.order}  # fmt: skip
        atomic_write(path, lambda fh: np.savez(
            fh, header=np.array(json.dumps(header)), gram=self.gram,
            baseline_rms=self.baseline_rms, floors=self.floors))  # fmt: skip

    @classmethod
    def load(cls, path: str | Path) -> TransferPredictor:
        try:
            with np.load(path, allow_pickle=False) as z:
                header = json.loads(str(z["header"]))
                arrays = {k: np.array(z[k]) for k in ("gram", "baseline_rms", "floors")}
        except (OSError, ValueError, KeyError) as exc:
            raise TransferInputError(f"{path}: not a transfer predictor file ({exc})") from None
        if header.get("format") != FORMAT:
            raise TransferInputError(f"{path}: format {header.get('format')!r}, not {FORMAT}")
        return cls(tuple(header["manoeuvres"]), tuple(header["outputs"]),
                   tuple(tuple(c) for c in header["components"]), float(header["size_pct"]),
                   order=int(header.get("order", 1)), **arrays)  # fmt: skip


def relative_pct(rms: np.ndarray, baseline: np.ndarray, floors: np.ndarray) -> np.ndarray:
    """100 rms / baseline where the baseline's RMS is at least its output's floor, else NaN
    (the vehicle comparison's rule, ``compare.relative``)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        pct = 100.0 * rms / baseline
    return np.where(baseline >= floors, pct, np.nan)


def basis(plus: list[np.ndarray], minus: list[np.ndarray] | None) -> list[np.ndarray]:
    """The basis histories of one manoeuvre and output: ``plus`` (first order) or the odd and
    even parts of ``plus`` and ``minus`` (second order), each (n, k)."""
    if minus is None:
        return list(plus)
    odd = [(p - m) / 2 for p, m in zip(plus, minus, strict=True)]
    return odd + [(p + m) / 2 for p, m in zip(plus, minus, strict=True)]


def gram_matrix(histories: list[np.ndarray]) -> np.ndarray:
    """(J, J) mean over time of the products of J difference histories, each (n, k)."""
    d = np.stack([h.reshape(h.shape[0], -1) for h in histories])  # (J, n, k)
    n = d.shape[1]
    flat = d.reshape(d.shape[0], -1)
    return flat @ flat.T / max(n, 1)


def check_cells(measured: np.ndarray, predicted: np.ndarray, least_pct: float) -> dict[str, Any]:
    """The predictor's error over cells (any shape, % of the reference's RMS; NaN where not
    stated): relative error |predicted - measured| / measured where the measured change is at
    least ``least_pct``, its median and 90th percentile, and Spearman's rank correlation of
    predicted and measured over the same cells."""
    m, p = np.ravel(measured), np.ravel(predicted)
    ok = np.isfinite(m) & np.isfinite(p) & (m >= least_pct)
    out: dict[str, Any] = {"cells": int(ok.sum()), "left_out_below_least": int(
        (np.isfinite(m) & (m < least_pct)).sum()), "least_pct": least_pct}  # fmt: skip
    if not ok.any():
        return {**out, "median_relative_error": None, "p90_relative_error": None,
                "spearman": None}  # fmt: skip
    rel = np.abs(p[ok] - m[ok]) / m[ok]
    rho = float(spearmanr(p[ok], m[ok]).statistic) if ok.sum() >= 3 else None
    return {**out, "median_relative_error": float(np.median(rel)),
            "p90_relative_error": float(np.percentile(rel, 90)), "spearman": rho}  # fmt: skip


def influence(pct: np.ndarray) -> np.ndarray:
    """(J,) each component's influence: the mean over the stated (manoeuvre, output) cells of
    its RMS change (%), from ``pct`` (J, M, O); outputs stated nowhere are left out."""
    stated = np.all(np.isfinite(pct), axis=0)
    return pct[:, stated].mean(axis=1) if stated.any() else np.zeros(0)


def influence_rank(measured: np.ndarray, predicted: np.ndarray) -> dict[str, Any]:
    """Spearman's rank correlation of the components' influence (``influence``), measured
    against predicted, overall and per output (last axis of the (J, M, O) arrays)."""
    per = {}
    for o in range(measured.shape[2]):
        a, b = influence(measured[:, :, o : o + 1]), influence(predicted[:, :, o : o + 1])
        if a.size and np.all(np.isfinite(a)) and np.ptp(a) > 0:
            per[o] = float(spearmanr(a, b).statistic)
    a, b = influence(measured), influence(predicted)
    rho = float(spearmanr(a, b).statistic) if a.size >= 3 and np.ptp(a) > 0 else None
    return {"overall": rho, "per_output": per}
