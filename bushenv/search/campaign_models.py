"""Which models a campaign judges, against what, at which scales.

For the built-in rubber (the reference by default when the model under attack is a registered
name) the hybrid and the control are the shipped hybrid and the papers' Table-1 linear model.
For a user's bushing they are models *of that bushing*: the hybrid only when given
(``--hybrid FILE``), the control a linear model fitted by least squares to the reference's
response on a random record within the bushing's stroke (with no reference: none, unless
given). Rows of another bushing's models would say nothing about this one.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bushenv import excitation as ex
from bushenv.identify.linear import least_squares_kc
from bushenv.judge import card_of
from bushenv.models import MODELS
from bushenv.models.base import velocity_of
from bushenv.models.linear import LinearBushing
from bushenv.scales import BushingScales

FITTED_CONTROL = "linear-fit"  # the control's spec while it is fitted; its file once saved
CONTROL_RECORD_S = 40.0  # the papers' identification record length (seed 000 §4.1)


def roles(config, judge, notes: list[str]) -> list[tuple[str, str]]:
    """(role, spec) for the target, the hybrid (when there is one), the control and, for a
    target whose registry entry names them, the models rechecked beside it (``also``)."""
    builtin = judge.builtin
    entry = MODELS.get(config.model) if config.model in MODELS else None
    out = [("target", config.model)]
    if config.hybrid is not None:
        out.append(("hybrid", config.hybrid))
    elif builtin:
        out.append(("hybrid", (entry and entry.hybrid) or "hybrid"))
    else:
        notes.append(
            "no hybrid row: the shipped hybrid is a model of the built-in rubber, not of this "
            "bushing (give yours with --hybrid FILE)"
        )
    if config.control is not None:
        out.append(("control", config.control))
    elif builtin:
        out.append(("control", "linear"))
    elif judge.reference is not None:
        notes.append(
            "control: a linear model fitted by least squares to the reference's response to "
            "the records of its model card (without a card: a "
            f"{CONTROL_RECORD_S:.0f} s random record within the bushing's stroke)"
        )
        out.append(("control", FITTED_CONTROL))
    else:
        notes.append(
            "no control row: without a reference there is no bushing to fit a linear control "
            "to (give --reference, or --control FILE)"
        )
    if builtin and entry is not None:
        out += [("also", name) for name in entry.also]
    return out


def card_displacements(spec: str | None) -> list[np.ndarray] | None:
    """The displacement of the training records a reference file's card names, when they are
    all still there (checked against the card's hashes), else None."""
    card = card_of(spec)
    if card is None:
        return None
    paths = [r.get("file") for r in card["records"] if r.get("role") == "train"]
    if not paths or not all(p and Path(p).is_file() for p in paths):
        return None
    from bushenv.identify.card import load_card
    from bushenv.records import load_csv

    load_card(spec, records=paths)  # CardError naming a record that changed since
    return [load_csv(p).displacement for p in paths]


def fitted_linear(
    source, scales: BushingScales, displacements: list | None = None, seed: int = 0
) -> LinearBushing:
    """Least-squares Kelvin-Voigt fit of ``source``'s response, from rest, to
    ``displacements`` (the records the reference was identified on, so the control sees the
    same band), else to an n = 1 random record scaled to the bushing's stroke (the papers'
    n = 1 peak is 2 mm of a 12.5 mm stroke)."""
    dt = source.dt
    if not displacements:
        x = ex.random_rpc(1.0, CONTROL_RECORD_S, dt, seed)
        x = x * (scales.stroke_m / ex.MAX_DISPLACEMENT_M)
        speed = np.max(np.abs(np.diff(x))) / dt
        if speed > scales.velocity_m_per_s:
            x = x * (scales.velocity_m_per_s / speed)
        displacements = [x]
    xs, vs, fs = [], [], []
    for x in displacements:
        v = velocity_of(np.asarray(x, dtype=np.float64), dt)
        xs.append(x)
        vs.append(v)
        fs.append(source.copy().simulate(x, v))
    k, c = least_squares_kc(np.concatenate(xs), np.concatenate(fs), np.concatenate(vs))
    return LinearBushing(k_n_per_m=k, c_ns_per_m=c, dt=dt)
