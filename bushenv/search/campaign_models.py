"""Which models a campaign judges, against what, at which scales.

For the built-in rubber (the reference by default when the model under attack is a registered
name) the hybrid and the control are the shipped hybrid and the papers' Table-1 linear model.
For a user's bushing they are models *of that bushing*: the hybrid only when given
(``--hybrid FILE``), the control a linear model fitted by least squares to the reference's
response on a random record within the bushing's stroke (with no reference: none, unless
given). Rows of another bushing's models would say nothing about this one.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from bushenv import excitation as ex
from bushenv.identify.linear import least_squares_kc
from bushenv.models import MODELS
from bushenv.models.base import velocity_of
from bushenv.models.linear import LinearBushing
from bushenv.scales import (
    BushingScales,
    scales_of_card,
    scales_of_reference,
    static_identified,
)

FITTED_CONTROL = "linear-fit"  # the control's spec while it is fitted; its file once saved
CONTROL_RECORD_S = 40.0  # the papers' identification record length (seed 000 §4.1)


def roles(config, notes: list[str]) -> list[tuple[str, str]]:
    """(role, spec) for the target, the hybrid (when there is one) and the control."""
    builtin = builtin_reference(config)
    out = [("target", config.model)]
    if config.hybrid is not None:
        out.append(("hybrid", config.hybrid))
    elif builtin:
        out.append(("hybrid", "hybrid"))
    else:
        notes.append(
            "no hybrid row: the shipped hybrid is a model of the built-in rubber, not of this "
            "bushing (give yours with --hybrid FILE)"
        )
    if config.control is not None:
        out.append(("control", config.control))
    elif builtin:
        out.append(("control", "linear"))
    elif config.reference is not None:
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
    return out


def builtin_reference(config) -> bool:
    """The campaign judges against the built-in rubber: asked for, or by default for a
    registered model (the shipped models are models of it)."""
    if config.reference is None:
        return config.model in MODELS
    return config.reference == "rubber"


def reference_spec(config) -> str | None:
    """The reference the campaign is judged against: as given; by default the rubber for a
    registered model; None (judged without one) for a model file."""
    if config.reference is None:
        return "rubber" if config.model in MODELS else None
    return config.reference


def static_trusted(config) -> bool:
    """Whether the reference's static force may judge (``scales.static_identified``)."""
    card = _card_of(reference_spec(config))
    return card is None or static_identified(card)


def campaign_scales(config, reference, builtin: bool) -> BushingScales:
    """The reference's scales (``bushenv.scales``), its model card's records' range when it
    is a file with a card beside it, and the flags' values on top of both."""
    scales = scales_of_reference(reference, builtin)
    # the reference's card; with no reference, the card of the model under attack: its records
    # are the only word on the bushing's range
    card = _card_of(reference_spec(config) if reference is not None else config.model)
    if card is not None:
        scales = scales_of_card(scales, card)
    flags = {
        "stroke_m": None if config.stroke_mm is None else config.stroke_mm * 1e-3,
        "velocity_m_per_s": config.max_velocity_m_per_s,
        "force_floor_n": config.force_floor_n,
        "force_scale_n": config.force_scale_n,
    }
    given = {k: v for k, v in flags.items() if v is not None}
    if not given:
        return scales
    return replace(scales, **given, source=scales.source + f"; flags: {sorted(given)}")


def _card_of(spec: str | None) -> dict | None:
    """The model card beside a reference file (checked against the file), or None."""
    if spec is None or spec in MODELS or not Path(spec).is_file():
        return None
    from bushenv.identify.card import card_paths, load_card

    if not card_paths(spec)[0].is_file():
        return None
    return load_card(spec).data


def card_displacements(spec: str | None) -> list[np.ndarray] | None:
    """The displacement of the training records a reference file's card names, when they are
    all still there (checked against the card's hashes), else None."""
    card = _card_of(spec)
    if card is None:
        return None
    from bushenv.identify.card import card_paths, load_card
    from bushenv.records import load_csv

    # record files are relative to the card (older cards: absolute)
    here = card_paths(spec)[0].parent
    paths = [here / r["file"] for r in card["records"] if r.get("role") == "train" and r["file"]]
    if not paths or not all(p.is_file() for p in paths):
        return None

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
