"""Which combinations of coordinates a model's training records showed it, and where a use goes
beyond them.

A bushing of C > 1 coordinates is used the way a vehicle loads it: one coordinate held at a
preload while another moves (a radial sweep under a held rotation, an axial preload under
radial travel). Random records on all axes at once rarely hold anything still, so a model
fitted on them has never settled at a held deflection of one coordinate while another moved:
its card's figures say nothing about that use (the planar hybrid of the three-axis benchmark:
1.3 / 6.0 / 0.3 % on its held-out random record, 27.9 % radial on a radial sweep under a held
rotation inside its range).

A *held combination* (h, m, sign) is a window of ``WINDOW_S`` in which coordinate h stays
within ``STILL`` of its training span around a level beyond ``HELD`` of the span, of that
sign, while coordinate m travels more than ``MOVING`` of its span. ``held_combinations``
lists them in records; the card keeps the training records' (``coverage``), and
``not_shown`` names those a use record holds that training never did.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

WINDOW_S = 0.5  # a hold lasts at least this long (the slow branches settle over it)
STILL = 0.1  # a held coordinate moves less than this share of its training span in a window
HELD = 0.25  # ...at a level beyond this share of its span
MOVING = 0.25  # a moving coordinate travels more than this share of its span in the window
SIGNS = ("+", "-")


def spans(records: Sequence[np.ndarray]) -> np.ndarray:
    """(C,) the largest |deflection| per coordinate over ``records`` ((T, C) each)."""
    return np.max([np.abs(q).max(axis=0) for q in records], axis=0)


def held_combinations(
    q: np.ndarray, dt: float, span: np.ndarray, coords: Sequence[str]
) -> dict[str, float]:
    """The held combinations of record ``q`` (T, C), as ``"h held +, m moving"`` -> the largest
    held level over the span (C = 1: none). Windows of ``WINDOW_S`` step by half a window."""
    q = np.asarray(q, dtype=np.float64)
    n = max(2, int(round(WINDOW_S / dt)))
    out: dict[str, float] = {}
    if q.ndim != 2 or q.shape[1] < 2 or q.shape[0] < n:
        return out
    scale = np.where(span > 0, span, np.inf)
    for start in range(0, q.shape[0] - n + 1, max(1, n // 2)):
        w = q[start : start + n] / scale
        travel = w.max(axis=0) - w.min(axis=0)
        level = w.mean(axis=0)
        for h in range(w.shape[1]):
            if travel[h] >= STILL or abs(level[h]) <= HELD:
                continue
            for m in range(w.shape[1]):
                if m != h and travel[m] > MOVING:
                    key = combination(coords[h], "+" if level[h] > 0 else "-", coords[m])
                    out[key] = max(out.get(key, 0.0), float(abs(level[h])))
    return out


def combination(held: str, sign: str, moving: str) -> str:
    return f"{held} held {sign}, {moving} moving"


def every_combination(coords: Sequence[str]) -> list[str]:
    """Every held combination a C-coordinate bushing can be used in (C (C - 1) x 2 signs)."""
    return [combination(h, s, m) for h in coords for s in SIGNS for m in coords if m != h]


def coverage(records: Sequence[np.ndarray], dt: float, coords: Sequence[str]) -> dict[str, Any]:
    """The card's ``coverage``: the training span per coordinate, the held combinations the
    records show (with the largest held level over the span) and those they never show."""
    span = spans(records)
    shown: dict[str, float] = {}
    for q in records:
        for key, level in held_combinations(q, dt, span, coords).items():
            shown[key] = max(shown.get(key, 0.0), level)
    return {
        "span": {c: float(s) for c, s in zip(coords, span, strict=True)},
        "held_shown": dict(sorted(shown.items())),
        "held_not_shown": [k for k in every_combination(coords) if k not in shown],
        "rule": (
            f"a coordinate held (moving < {STILL:.0%} of its span for {WINDOW_S:g} s, beyond "
            f"{HELD:.0%} of it) while another travels > {MOVING:.0%} of its span"
        ),
    }


def not_shown(card_coverage: dict[str, Any], q: np.ndarray, dt: float) -> dict[str, float]:
    """The held combinations of a use record ``q`` (T, C) that the training records never
    showed, judged on the training span -> the largest held level over that span."""
    coords = list(card_coverage["span"])
    span = np.array([card_coverage["span"][c] for c in coords])
    used = held_combinations(q, dt, span, coords)
    return {k: v for k, v in used.items() if k not in card_coverage["held_shown"]}


def coverage_summary(card_coverage: dict[str, Any]) -> list[str]:
    """The card's lines: what the training records held, and what they never did."""
    shown = card_coverage["held_shown"]
    missing = card_coverage["held_not_shown"]
    total = len(shown) + len(missing)
    lines = [
        f"combinations shown: {len(shown)} of {total} held combinations ({card_coverage['rule']})"
    ]
    if shown:
        lines.append("  held in training: " + "; ".join(sorted(shown)))
    if missing:
        lines.append(
            "  never shown: " + "; ".join(missing) + " -- the card's figures do not judge these "
            "uses (bushenv measure --axes 3 --programme combined records all of them)"
        )
    return lines
