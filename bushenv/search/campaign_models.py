"""Which models a campaign judges, against what, at which scales.

For the built-in rubber (the reference by default when the model under attack is a registered
name) the hybrid and the control are the shipped hybrid and the papers' Table-1 linear model.
For a user's bushing they are models *of that bushing*: the hybrid only when given
(``--hybrid FILE``), the control a linear model fitted by least squares to the reference's
response on a random record within the bushing's stroke (with no reference: none, unless
given). Rows of another bushing's models would say nothing about this one.
"""

from __future__ import annotations

import numpy as np

from bushenv.identify.linear import CONTROL_RECORD_S, fitted_linear  # noqa: F401 (re-export)
from bushenv.judge import Judge
from bushenv.models import MODELS
from bushenv.resolved import ResolvedModel
from bushenv.search.campaign_config import CampaignConfig

FITTED_CONTROL = "linear-fit"  # the control's spec while it is fitted; its file once saved


def roles(
    config: CampaignConfig, judge: Judge, notes: list[str], coords: int = 1
) -> list[tuple[str, str]]:
    """(role, spec) for the target, the hybrid (when there is one), the control and, for a
    target whose registry entry names them, the models rechecked beside it (``also``); over
    ``coords`` coordinates, of the built-in's models only those there without a file."""
    builtin = judge.builtin
    entry = MODELS.get(config.model) if config.model in MODELS else None
    out = [("target", config.model)]
    shipped_hybrid = (entry and entry.hybrid) or "hybrid"
    if config.hybrid is not None:
        out.append(("hybrid", config.hybrid))
    elif builtin and MODELS[shipped_hybrid].ready_made(coords):
        out.append(("hybrid", shipped_hybrid))
    elif builtin:
        notes.append(
            f"no hybrid row: no {shipped_hybrid} over {coords} coordinates ships with bushenv "
            "(a network must be trained: give yours with --hybrid FILE)"
        )
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
            "the records of its model card (without a card: the model's card's, else a "
            f"{CONTROL_RECORD_S:.0f} s random record within the bushing's stroke)"
        )
        out.append(("control", FITTED_CONTROL))
    else:
        notes.append(
            "no control row: without a reference there is no bushing to fit a linear control "
            "to (give --reference, or --control FILE)"
        )
    if builtin and entry is not None:
        out += [("also", name) for name in entry.also if MODELS[name].ready_made(coords)]
    return out


def card_records(resolved: ResolvedModel | None) -> list | None:
    """The training records (``Record``, of the model's number of coordinates) the card of
    ``resolved`` names, when they are all still there (checked against the card's hashes, with
    the card read once, at resolving; a record made in memory has no file and is left out),
    else None."""
    if resolved is None or resolved.card is None:
        return None
    from bushenv.identify.card import ModelCard
    from bushenv.record_files import load_record

    card = ModelCard(resolved.card_file, resolved.card)
    train = [card.record_path(r) for r in card.records if r.get("role") == "train"]
    paths = [p for p in train if p is not None]
    if not paths or not all(p.is_file() for p in paths):
        return None
    card.verify_records(paths)  # CardError naming a record that changed since
    return [load_record(p, coords=resolved.model.n_coords) for p in paths]


def card_displacements(resolved: ResolvedModel | None) -> list[np.ndarray] | None:
    """The displacement of each of ``card_records`` ((T,), or (T, C) over C coordinates), or
    None."""
    records = card_records(resolved)
    return None if records is None else [r.displacement for r in records]
