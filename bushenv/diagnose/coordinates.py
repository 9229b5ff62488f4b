"""The diagnosis over C coordinates: which coordinate carries a baseline's gap, which effect
closes it there, how far.

Records are any objects with ``.time`` (T,) s, ``.q`` (T, C) and ``.f`` (T, C) in the
coordinates' SI units (three-axis: m, m, rad and N, N, N m) and ``.dt`` s, such as
``bushenv.planar.records.PlanarRecord``. The steps:

1. **Baseline**: the linear model over C coordinates, ``f = K q + C v`` (C x C matrices, the
   ``linear`` form of ``bushenv.models.MODELS`` for C), identified on the TRAIN records.
2. **Per coordinate i**, the one-axis engine (``fit.diagnose``) runs unchanged on the record
   ``(q_i, f_i - sum_{j != i} (K_ij q_j + C_ij v_j))``: the coordinate's force less the
   baseline's cross-coordinate terms, which stay fixed. The engine's own linear baseline then
   refits the diagonal ``K_ii, C_ii`` with every candidate, as for one axis (k, c >= 0, every
   record used or held out), so the candidates take the coordinate's own deflection.
3. **Which coordinate**: each coordinate's gap on its measured force, ``rms(f_i - baseline_i) /
   rms(f_i)`` over the judged records (the residual of the C-coordinate baseline with its
   diagonal refitted as the engine judges it), ranked largest first; a coordinate **carries**
   a gap when the engine's answer there is not ``none`` (a gap clear of the force's noise). The
   answer is the carrying coordinate with the largest gap above the noise, and its effect.

Why the candidates see one coordinate only: every candidate is a one-axis physical form, and
an effect that is coupled in the specimen (a vector friction's yield surface, relaxation of a
coupled elastic force) shows on each coordinate as that coordinate's own effect, only less
exact; the linear cross-coordinate terms are the baseline's. A coupling of the elastic force
itself (a stiffness that depends on another coordinate's deflection) is no candidate: it is
answered ``outside_candidates`` on the coordinates it acts on (studies/2026-11-diagnose-three-axis).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from bushenv.diagnose.coupling import COUPLING_MIN, coupling_test
from bushenv.diagnose.errors import DiagnoseError
from bushenv.diagnose.inputs import LINEAR, MIN_SAMPLES, Progress, names_of
from bushenv.metrics import rms_ratio

RATE_RTOL = 1e-6  # records whose sample times differ by less share one rate
SI_TOKENS = {"m": "m", "rad": "rad", "N": "n", "N m": "nm"}  # unit -> its token in a key


@dataclass(frozen=True)
class CoordinateView:
    """One coordinate of a record as the one-axis engine takes it: (T,) arrays, s, SI."""

    time: np.ndarray
    displacement: np.ndarray
    force: np.ndarray
    dt: float
    name: str


def coordinate_count(rec: Any) -> int:
    """C of a record: 1 for a one-axis record (``.displacement``), q's last axis otherwise."""
    if hasattr(rec, "q") and hasattr(rec, "f"):
        q = np.asarray(rec.q)
        return int(q.shape[1]) if q.ndim == 2 else 1
    return 1


def coordinates_of(rec: Any, c: int) -> tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...]]:
    """(names, displacement units, force units) of the C coordinates: the record's own
    ``coords`` / ``units`` / ``force_units`` if it has them, the three-axis bushing's for C = 3."""
    from bushenv.planar.base import COORDS, FORCE_UNITS, UNITS

    if c == 3:
        default = (COORDS, UNITS, FORCE_UNITS)
    else:
        default = (tuple(f"q{i + 1}" for i in range(c)), ("m",) * c, ("N",) * c)
    attrs = ("coords", "units", "force_units")
    names, units, force_units = (
        tuple(getattr(rec, a, None) or d) for a, d in zip(attrs, default, strict=True)
    )
    return names, units, force_units


def check_coordinate_records(trains: list, tests: list, t_names: list, names: list) -> int:
    """C shared by every record; ``DiagnoseError`` naming a record of another count or shape."""
    labelled = [(f"TRAIN {n}", r) for n, r in zip(t_names, trains, strict=True)]
    labelled += [(f"TEST {n}", r) for n, r in zip(names, tests, strict=True)]
    counts = {label: coordinate_count(r) for label, r in labelled}
    c = counts[labelled[0][0]]
    for label, k in counts.items():
        if k != c:
            first = labelled[0][0]
            raise DiagnoseError(
                f"{label} has {k} coordinate(s) but {first} has {c}: one diagnosis takes "
                "records of one kind (all one-axis or all three-axis)"
            )
    dt0 = float(trains[0].dt)
    for label, rec in labelled:
        q, f = np.asarray(rec.q, float), np.asarray(rec.f, float)
        n = np.size(rec.time)
        if q.shape != (n, c) or f.shape != (n, c):
            raise DiagnoseError(
                f"{label}: q and f must be ({n}, {c}) arrays, got {q.shape} and {f.shape}"
            )
        if n < MIN_SAMPLES:
            raise DiagnoseError(f"{label}: {n} samples; the diagnosis needs at least {MIN_SAMPLES}")
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(f))):
            raise DiagnoseError(f"{label}: q or f holds NaN or inf")
        if abs(float(rec.dt) - dt0) > RATE_RTOL * dt0:
            raise DiagnoseError(
                f"{label}: sampled at {1 / rec.dt:.6g} Hz but {labelled[0][0]} at {1 / dt0:.6g} "
                f"Hz; the {c}-coordinate baseline is identified at one rate: resample the "
                "records to one rate first"
            )
    return c


def linear_baseline(trains: list, c: int, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """(K, C) of the ``linear`` form over ``c`` coordinates identified on ``trains``."""
    from bushenv.identify.options import options_of
    from bushenv.models import MODELS

    form = MODELS[LINEAR].form(c)
    opts = options_of(form.options_class(), None, LINEAR)
    hist = [(np.asarray(r.q, float), np.asarray(r.f, float)) for r in trains]
    model, _ = form.fit_function()(hist, dt, opts, 0, None)
    return np.asarray(model.k_matrix, float), np.asarray(model.c_matrix, float)


def cross_terms(q: np.ndarray, dt: float, k: np.ndarray, c: np.ndarray) -> np.ndarray:
    """(T, C): per coordinate i, sum over j != i of K_ij q_j + C_ij v_j (v by ``velocity_of``)."""
    from bushenv.models.base import velocity_of

    off_k, off_c = k - np.diag(np.diag(k)), c - np.diag(np.diag(c))
    return q @ off_k.T + velocity_of(q, dt) @ off_c.T


def unit_keys(obj: Any, unit: str, force_unit: str) -> Any:
    """``obj`` with the SI units in its keys read for a coordinate in ``unit`` and
    ``force_unit`` (``k_n_per_m`` becomes ``k_nm_per_rad`` for a rotation); unchanged for m, N."""
    if (unit, force_unit) == ("m", "N"):
        return obj
    d, f = SI_TOKENS.get(unit, unit), SI_TOKENS.get(force_unit, force_unit)

    def key(k: str) -> str:
        k = k.replace("_ns_per_m", f"_{f}s_per_{d}").replace("_n_per_m", f"_{f}_per_{d}")
        k = k.replace("_per_m", f"_per_{d}").replace("_m_per_s", f"_{d}_per_s")
        k = re.sub(r"_n$", f"_{f}", re.sub(r"_m$", f"_{d}", k))
        return k.replace("mass_kg", "inertia_kg_m2") if d == "rad" else k

    if isinstance(obj, dict):
        return {key(k): unit_keys(v, unit, force_unit) for k, v in obj.items()}
    if isinstance(obj, list):
        return [unit_keys(v, unit, force_unit) for v in obj]
    return obj


def _unit_text(text: str, unit: str) -> str:
    """A sentence the engine wrote in mm (1e3 x the deflection), read for ``unit``."""
    return text if unit == "m" else re.sub(r"\bmm\b", f"m{unit}", text)


# ----- the diagnosis ---------------------------------------------------------------------------
def diagnose_coordinates(
    train: Any,
    tests: Sequence[Any],
    baseline: str = LINEAR,
    progress: Progress | None = None,
    seed: int = 0,
    test_names: Sequence[str] | None = None,
    *,
    cross: bool | None = None,
    effects: Sequence[str] | None = None,
    train_names: Sequence[str] | None = None,
) -> dict[str, Any]:
    """Which coordinate carries the gap, which effect closes it there, how far (module doc).

    Returns a JSON-ready dict (docs/diagnose.md, "Three-axis records") plus ``"predictions"``
    (per judged record: ``time`` (T,), ``q``, ``force_measured``, ``force_baseline``,
    ``force_augmented`` (T, C)) and ``"diagnoses"``: per coordinate, the one-axis engine's
    whole result on that coordinate (with its own predictions).
    """
    from bushenv.diagnose.fit import diagnose

    say = progress or (lambda msg: None)
    trains = list(train) if isinstance(train, list | tuple) else [train]
    if not trains:
        raise DiagnoseError("no TRAIN record given")
    if not tests:
        raise DiagnoseError("no TEST record given; the gap is judged on held-out records only")
    t_names = names_of(trains, train_names, "train")
    names = names_of(tests, test_names, "test")
    c = check_coordinate_records(trains, list(tests), t_names, names)
    if baseline != LINEAR:
        raise DiagnoseError(
            f"baseline {baseline!r}: records of {c} coordinates are diagnosed against the linear "
            f"{c}-coordinate baseline (K and C matrices); --baseline {baseline} takes one-axis "
            "records"
        )
    coords, units, force_units = coordinates_of(trains[0], c)
    dt = float(trains[0].dt)
    say(f"identifying the linear {c}-coordinate baseline on TRAIN ({len(trains)} record(s))")
    k, cm = linear_baseline(trains, c, dt)
    recs = [(n, "train", r) for n, r in zip(t_names, trains, strict=True)]
    recs += [(n, "test", r) for n, r in zip(names, tests, strict=True)]
    cross_of = {n: cross_terms(np.asarray(r.q, float), dt, k, cm) for n, _, r in recs}
    diagnoses: dict[str, dict] = {}
    couplings: dict[str, dict] = {}
    for i, name in enumerate(coords):
        views = {
            n: CoordinateView(
                np.asarray(r.time, float),
                np.asarray(r.q, float)[:, i],
                np.asarray(r.f, float)[:, i] - cross_of[n][:, i],
                float(r.dt),
                n,
            )
            for n, _, r in recs
        }
        say(f"coordinate {name} ({i + 1}/{c})")
        diagnoses[name] = d = diagnose(
            [views[n] for n in t_names],
            [views[n] for n in names],
            progress=lambda msg, name=name: say(f"{name}: {msg}"),
            seed=seed,
            test_names=names,
            train_names=t_names,
            cross=cross,
            effects=effects,
        )
        d["coordinate"] = name
        couplings[name] = _coupling(recs, cross_of, i, list(coords), diagnoses[name])
        say(f"{name}: coupling terms close {100 * couplings[name]['closes']:.0f} % beyond its own")
    by_name = {n: r for n, _, r in recs}
    rows = [
        _coordinate_row(units[i], force_units[i], i, diagnoses[c], by_name, cross_of, couplings[c])
        for i, c in enumerate(coords)
    ]
    return _result(rows, diagnoses, coords, units, force_units, k, cm, recs, cross_of, t_names)


def _coupling(recs: list, cross_of: dict, i: int, coords: list[str], d: dict) -> dict[str, Any]:
    """The coupling test on coordinate ``i`` (``coupling.py``), on the engine's folds; named
    where the one-axis diagnosis found a gap clear of the noise that no candidate closes."""
    records = {
        n: {"q": np.asarray(r.q, float), "force": np.asarray(r.f, float)[:, i] - cross_of[n][:, i],
            "dt": float(r.dt)}
        for n, _, r in recs
    }  # fmt: skip
    test = coupling_test(records, d["records"]["folds"], i, coords, d["gap_noise"])
    test["named"] = bool(
        d["effect"] == "outside_candidates"
        and test["closes"] >= COUPLING_MIN
        and test["gap_coupled"] < test["gap_null"]
    )
    return test


def augmented(pred: dict[str, Any], coupling: dict[str, Any]) -> np.ndarray:
    """The judged prediction of the answer's model on one record: the coupled fit where
    ``coupling`` is named, else the engine's (both less the cross-coordinate terms)."""
    if coupling["named"]:
        return coupling["predictions"][pred["name"]]
    return pred["force_augmented"]


def _coordinate_row(unit, force_unit, i, d, by_name, cross_of, coupling) -> dict[str, Any]:
    """One coordinate's numbers on its measured force (the cross-coordinate terms added back)."""
    preds = d["predictions"]
    name = d.get("coordinate") or ""
    cross = np.concatenate([cross_of[p["name"]][:, i] for p in preds])
    f = np.concatenate([np.asarray(by_name[p["name"]].f, float)[:, i] for p in preds])
    base = cross + np.concatenate([p["force_baseline"] for p in preds])
    aug = cross + np.concatenate([augmented(p, coupling) for p in preds])
    rms_f = float(np.sqrt(np.mean(f**2)))
    rms_adj = float(np.sqrt(np.mean(np.concatenate([p["force_measured"] for p in preds]) ** 2)))
    gap_before, gap_after = rms_ratio(f, base), rms_ratio(f, aug)
    noise = d["gap_noise"] * rms_adj / rms_f if rms_f > 0 else 0.0
    shown = {k: v for k, v in coupling.items() if k != "predictions"}
    return {
        "coordinate": name,
        "unit": unit,
        "force_unit": force_unit,
        "effect": "coupling" if coupling["named"] else d["effect"],
        "effect_one_axis": d["effect"],
        "coupled_to": coupling["partners"] if coupling["named"] else [],
        "coupling": shown,
        "carries_gap": d["effect"] != "none",
        "top_two": d["top_two"],
        "ambiguous_between": d["ambiguous_between"],
        "gap_before": gap_before,
        "gap_after": gap_after,
        "shrink": 1.0 - gap_after / gap_before if gap_before > 0 else 0.0,
        "gap_noise": noise,
        "excess_gap": float(np.sqrt(max(gap_before**2 - noise**2, 0.0))),
        "rms_force": rms_f,
        "cross_share": float(np.sqrt(np.mean(cross**2))) / rms_f if rms_f > 0 else 0.0,
        "report": f"{name}/report.md",
        "_coupling": coupling,
    }


def _result(rows, diagnoses, coords, units, force_units, k, cm, recs, cross_of, t_names):
    total = sum(r["excess_gap"] ** 2 for r in rows)
    for r in rows:
        r["share_above_noise"] = r["excess_gap"] ** 2 / total if total > 0 else 0.0
    ranked = sorted(rows, key=lambda r: -r["gap_before"])
    carrying = sorted((r for r in rows if r["carries_gap"]), key=lambda r: -r["excess_gap"])
    top = carrying[0] if carrying else None
    first = diagnoses[coords[0]]
    for name, unit, fu in zip(coords, units, force_units, strict=True):
        d = diagnoses[name]
        d["units"] = {"displacement": unit, "force": fu}
        d["parameters"] = unit_keys(d["parameters"], unit, fu)
        for w in d["shift_warnings"]:
            w["text"] = _unit_text(w["text"], unit)
        i = coords.index(name)
        others = ", ".join(c for c in coords if c != name)
        d["notes"].insert(
            0,
            f"coordinate {name} of a {len(coords)}-coordinate diagnosis: the force here is "
            f"{name}'s ({fu}) less the linear baseline's cross-coordinate terms from {others} "
            f"(fixed, identified on TRAIN: {100 * _row(rows, name)['cross_share']:.2f} % of its "
            f"RMS); deflection in {unit}, parameters in {unit} and {fu}. K row: "
            f"{np.array2string(k[i], precision=6)}, C row: {np.array2string(cm[i], precision=6)}",
        )
        c_test = _row(rows, name)["coupling"]
        if c_test["named"] or c_test["closes"] >= COUPLING_MIN:
            d["notes"].insert(1, _coupling_note(name, c_test))
    judged = first["records"]["judged"]
    by_name = {n: r for n, _, r in recs}
    predictions = []
    for j, n in enumerate(judged):
        rows_by = {r["coordinate"]: r for r in rows}
        base = np.stack([diagnoses[c]["predictions"][j]["force_baseline"] for c in coords], 1)
        aug = np.stack(
            [augmented(diagnoses[c]["predictions"][j], rows_by[c]["_coupling"]) for c in coords], 1
        )
        cols = {"force_baseline": base + cross_of[n], "force_augmented": aug + cross_of[n]}
        predictions.append(
            {
                "name": n,
                "role": first["predictions"][j]["role"],
                "dt": first["predictions"][j]["dt"],
                "time": first["predictions"][j]["time"],
                "q": np.asarray(by_name[n].q, float),
                "force_measured": np.asarray(by_name[n].f, float),
                **cols,
            }
        )
    for r in rows:
        del r["_coupling"]
    if top is None:
        answer = "none: the baseline explains every coordinate down to the force's noise"
    else:
        answer = f"{top['coordinate']}: {top['effect']}"
        if top["coupled_to"]:
            answer += f" (to {', '.join(top['coupled_to'])})"
        elif top["ambiguous_between"]:
            answer += f" ({' or '.join(top['ambiguous_between'])})"
    return {
        "coordinate": top["coordinate"] if top else None,
        "effect": top["effect"] if top else "none",
        "answer": answer,
        "coordinates_carrying_gap": [r["coordinate"] for r in carrying],
        "effects": {r["coordinate"]: r["effect"] for r in rows},
        "gap_before": top["gap_before"] if top else max(r["gap_before"] for r in rows),
        "gap_after": top["gap_after"] if top else max(r["gap_before"] for r in rows),
        "shrink": top["shrink"] if top else 0.0,
        "coords": list(coords),
        "units": list(units),
        "force_units": list(force_units),
        "baseline": LINEAR,
        "baseline_model": {
            "k_matrix": k.tolist(),
            "c_matrix": cm.tolist(),
            "identified_on": list(t_names),
            "text": f"f = K q + C v over the {len(coords)} coordinates (least squares on TRAIN); "
            "each coordinate's diagonal K_ii, C_ii is refitted with every candidate, the "
            "cross-coordinate terms stay fixed",
        },
        "mode": first["mode"],
        "mode_text": first["mode_text"],
        "coordinates": ranked,
        "rule": COORDINATE_RULE,
        "records": {k_: v for k_, v in first["records"].items()},
        "notes": [n for n in first["notes"] if not n.startswith("coordinate ")],
        "predictions": predictions,
        "diagnoses": diagnoses,
    }


def _row(rows: list[dict], name: str) -> dict:
    return next(r for r in rows if r["coordinate"] == name)


def _coupling_note(name: str, test: dict[str, Any]) -> str:
    said = (
        "named coupling: no one-axis candidate closes the gap, and"
        if test["named"]
        else "besides the answer,"
    )
    return (
        f"three-axis coupling test on {name}: {said} the terms {name} x (other coordinate)^2 "
        f"close {100 * test['closes']:.0f} % of the gap above the noise beyond {name}'s own "
        f"cubic (gap {100 * test['gap_null']:.2f} % -> {100 * test['gap_coupled']:.2f} %), most "
        f"with {', '.join(test['partners']) or '-'}: a stiffness that follows another "
        "coordinate's deflection (bushenv/diagnose/coupling.py)"
    )


COORDINATE_RULE = (
    "each coordinate's gap is rms(f_i - baseline_i) / rms(f_i) over the judged records; a "
    "coordinate carries a gap when the one-axis diagnosis of it answers other than none (a gap "
    "clear of the force's noise); the answer is the carrying coordinate with the largest gap "
    "above the noise, sqrt(gap^2 - gap_noise^2), and the effect named there; where the one-axis "
    f"diagnosis answers outside_candidates and terms q_i q_j^2 close at least "
    f"{100 * COUPLING_MIN:.0f} % of the gap above the noise beyond the coordinate's own cubic, "
    "the effect is coupling (to the coordinates j whose term closes most)"
)
