"""Failure rates of a population with 95 % intervals, and the labels that group its members.

Rates are counts of members (one trained model each) out of the members of a group, with
Wilson's 95 % score interval: with 10 seeds per group a rate of 0/10 still allows up to 28 %.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

Z95 = 1.959963984540054


def wilson(k: int, n: int) -> tuple[float, float]:
    """Wilson score 95 % interval of a rate k / n (0, 1 for n = 0)."""
    if n == 0:
        return 0.0, 1.0
    p = k / n
    centre = (p + Z95**2 / (2 * n)) / (1 + Z95**2 / n)
    half = Z95 * math.sqrt(p * (1 - p) / n + Z95**2 / (4 * n * n)) / (1 + Z95**2 / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def rate(k: int, n: int) -> dict[str, Any]:
    lo, hi = wilson(k, n)
    return {"failed": k, "of": n, "rate": k / n if n else None, "ci95": [lo, hi]}


def pct(r: dict) -> str:
    lo, hi = r["ci95"]
    return f"{r['failed']}/{r['of']} ({100 * lo:.0f}-{100 * hi:.0f} %)"


def median_of(values) -> float | None:
    vals = [v for v in values if v is not None]
    return float(np.median(vals)) if vals else None


def shown_options(train_options: dict) -> list[str]:
    """The training switches that name a member's group: those on, and the planar structure
    and hybrid training when not the default (``certified``, ``mirror-rate``,
    ``noisy-feedback``)."""
    opts = sorted(train_options.items())
    return [k if v == "on" else v for k, v in opts if v == "on" or k in ("structure", "training")]


def recipe_label(row: dict) -> str:
    """The recipe with the training switches that are on (``free-run +certified``)."""
    return " +".join([row["recipe"], *shown_options(row.get("train_options", {}))])
