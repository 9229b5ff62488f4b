"""The answer of a diagnosis over C coordinates (``coordinates.py``): each coordinate's gap on
its measured force, the coordinate that carries the gap, its effect and shrink, the
predictions of every coordinate, and each coordinate's one-axis result read in its units."""

from __future__ import annotations

import re
from typing import Any

import numpy as np

from bushenv.diagnose.coupling import COUPLING_BEATS, COUPLING_MIN
from bushenv.metrics import rms_ratio

SI_TOKENS = {"m": "m", "rad": "rad", "N": "n", "N m": "nm"}  # unit -> its token in a key
NOT_DIAGNOSED = "not_diagnosed"

COORDINATE_RULE = (
    "each coordinate's gap is rms(f_i - baseline_i) / rms(f_i) over the judged records; a "
    "coordinate carries a gap when the one-axis diagnosis of it answers other than none (a gap "
    "clear of the force's noise); the answer is the carrying coordinate with the largest gap "
    "above the noise, sqrt(gap^2 - gap_noise^2), and the effect named there; where terms "
    f"q_i q_j^2 close at least {100 * COUPLING_MIN:.0f} % of the gap above the noise beyond the "
    "coordinate's own cubic and the one-axis diagnosis answers outside_candidates (or names an "
    f"effect leaving over {1 / COUPLING_BEATS:.2g} x the coupled fit's gap), the effect is "
    "coupling (to the coordinates j whose term closes most)"
)


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


def unit_text(text: str, unit: str) -> str:
    """A sentence the engine wrote in mm (1e3 x the deflection), read for ``unit``."""
    return text if unit == "m" else re.sub(r"\bmm\b", f"m{unit}", text)


def augmented(pred: dict[str, Any], coupling: dict[str, Any]) -> np.ndarray:
    """The judged prediction of the answer's model on one record: the coupled fit where
    ``coupling`` is named, else the engine's (both less the cross-coordinate terms)."""
    if coupling["named"]:
        return coupling["predictions"][pred["name"]]
    return pred["force_augmented"]


def _row(setup, i: int, d: dict[str, Any] | None, coupling: dict | None, left_out) -> dict:
    """One coordinate's numbers on its measured force (the cross-coordinate terms added back)."""
    name = setup.coords[i]
    row: dict[str, Any] = {
        "coordinate": name,
        "unit": setup.units[i],
        "force_unit": setup.force_units[i],
        "left_out": left_out,
    }
    if d is None:
        return row | {
            "effect": NOT_DIAGNOSED,
            "effect_one_axis": NOT_DIAGNOSED,
            "carries_gap": False,
            "top_two": [],
            "ambiguous_between": [],
            "coupled_to": [],
            "gap_before": None,
            "gap_after": None,
            "shrink": 0.0,
            "gap_noise": None,
            "excess_gap": 0.0,
            "report": None,
        }
    preds = d["predictions"]
    cross = np.concatenate([setup.cross[p["name"]][:, i] for p in preds])
    f = np.concatenate([setup.f(p["name"])[:, i] for p in preds])
    base = cross + np.concatenate([p["force_baseline"] for p in preds])
    aug = cross + np.concatenate([augmented(p, coupling) for p in preds])
    rms_f = float(np.sqrt(np.mean(f**2)))
    rms_adj = float(np.sqrt(np.mean(np.concatenate([p["force_measured"] for p in preds]) ** 2)))
    gap_before, gap_after = rms_ratio(f, base), rms_ratio(f, aug)
    noise = d["gap_noise"] * rms_adj / rms_f if rms_f > 0 else 0.0
    return row | {
        "effect": "coupling" if coupling["named"] else d["effect"],
        "effect_one_axis": d["effect"],
        "coupled_to": coupling["partners"] if coupling["named"] else [],
        "coupling": {k: v for k, v in coupling.items() if k != "predictions"},
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
    }


def _in_units(setup, i: int, d: dict[str, Any], row: dict[str, Any]) -> None:
    """The coordinate's one-axis result read in its units, with what it is a part of."""
    name, unit, fu = setup.coords[i], setup.units[i], setup.force_units[i]
    d["units"] = {"displacement": unit, "force": fu}
    d["parameters"] = unit_keys(d["parameters"], unit, fu)
    for w in d["shift_warnings"]:
        w["text"] = unit_text(w["text"], unit)
    others = ", ".join(c for c in setup.coords if c != name)
    notes = [
        f"coordinate {name} of a {len(setup.coords)}-coordinate diagnosis: the force here is "
        f"{name}'s ({fu}) less the linear baseline's cross-coordinate terms from {others} "
        f"(fixed, identified on TRAIN: {100 * row['cross_share']:.2f} % of its RMS); "
        f"deflection in {unit}, parameters in {unit} and {fu}. K row: "
        f"{np.array2string(setup.k[i], precision=6)}, C row: "
        f"{np.array2string(setup.c[i], precision=6)}"
    ]
    if row["left_out"]:
        notes.append(f"{name} does not move in {', '.join(row['left_out'])}: left out here")
    test = row["coupling"]
    if test["named"] or test["closes"] >= COUPLING_MIN:
        said = (
            f"named coupling ({row['effect_one_axis']} one axis), as"
            if test["named"]
            else "besides the answer,"
        )
        notes.append(
            f"three-axis coupling test on {name}: {said} the terms {name} x (other "
            f"coordinate)^2 close {100 * test['closes']:.0f} % of the gap above the noise beyond "
            f"{name}'s own cubic (gap {100 * test['gap_null']:.2f} % -> "
            f"{100 * test['gap_coupled']:.2f} %), most with {', '.join(test['partners']) or '-'}"
            ": a stiffness that follows another coordinate's deflection"
        )
    d["notes"] = notes + d["notes"]


def _predictions(setup, diagnoses: dict, couplings: dict) -> list[dict[str, Any]]:
    """Per record judged on some coordinate, (T, C) forces: measured, the baseline and the
    answer's model (the linear baseline's on a coordinate the record is not judged on)."""
    by = {
        (c, p["name"]): p for c, d in diagnoses.items() for p in d["predictions"]
    }  # (coordinate, record) -> the engine's prediction
    judged = [n for n in setup.records if any((c, n) in by for c in setup.coords)]
    out = []
    for n in judged:
        linear = setup.baseline(n)
        base, aug = linear.copy(), linear.copy()
        for i, c in enumerate(setup.coords):
            if (c, n) in by:
                base[:, i] = by[c, n]["force_baseline"] + setup.cross[n][:, i]
                aug[:, i] = augmented(by[c, n], couplings[c]) + setup.cross[n][:, i]
        out.append(
            {
                "name": n,
                "role": setup.roles[n],
                "dt": setup.dt(n),
                "time": np.asarray(setup.records[n].time, float),
                "q": setup.q(n),
                "force_measured": setup.f(n),
                "force_baseline": base,
                "force_augmented": aug,
            }
        )
    return out


def coordinate_result(setup, diagnoses: dict, couplings: dict, left_out: dict) -> dict[str, Any]:
    """The JSON-ready answer (docs/diagnose.md, "Three-axis records") with ``predictions``
    and ``diagnoses`` (each coordinate's one-axis result, read in its units)."""
    rows = []
    for i, c in enumerate(setup.coords):
        rows.append(_row(setup, i, diagnoses.get(c), couplings.get(c), left_out[c]))
        if c in diagnoses:
            _in_units(setup, i, diagnoses[c], rows[-1])
    total = sum(r["excess_gap"] ** 2 for r in rows)
    for r in rows:
        r["share_above_noise"] = r["excess_gap"] ** 2 / total if total > 0 else 0.0
    ranked = sorted(rows, key=lambda r: -(r["gap_before"] if r["gap_before"] is not None else -1))
    carrying = sorted((r for r in rows if r["carries_gap"]), key=lambda r: -r["excess_gap"])
    top = carrying[0] if carrying else None
    first = next(iter(diagnoses.values()))
    if top is None:
        answer = "none: the baseline explains every diagnosed coordinate down to the noise"
    else:
        answer = f"{top['coordinate']}: {top['effect']}"
        if top["coupled_to"]:
            answer += f" (to {', '.join(top['coupled_to'])})"
        elif top["ambiguous_between"]:
            answer += f" ({' or '.join(top['ambiguous_between'])})"
    gaps = [r["gap_before"] for r in rows if r["gap_before"] is not None]
    predictions = _predictions(setup, diagnoses, couplings)
    notes = [n for n in first["notes"] if not n.startswith(("coordinate ", "three-axis "))]
    notes = [n for n in notes if " does not move in " not in n]
    notes += [
        f"coordinate {r['coordinate']} is not diagnosed: it moves in no TRAIN or no TEST record"
        for r in rows
        if r["effect"] == NOT_DIAGNOSED
    ]
    records = dict(first["records"])
    records["judged"] = [p["name"] for p in predictions]
    records["per_coordinate"] = {c: d["records"]["judged"] for c, d in diagnoses.items()}
    return {
        "coordinate": top["coordinate"] if top else None,
        "effect": top["effect"] if top else "none",
        "answer": answer,
        "coordinates_carrying_gap": [r["coordinate"] for r in carrying],
        "effects": {r["coordinate"]: r["effect"] for r in rows},
        "gap_before": top["gap_before"] if top else max(gaps),
        "gap_after": top["gap_after"] if top else max(gaps),
        "shrink": top["shrink"] if top else 0.0,
        "coords": list(setup.coords),
        "units": list(setup.units),
        "force_units": list(setup.force_units),
        "baseline": "linear",
        "baseline_model": {
            "k_matrix": setup.k.tolist(),
            "c_matrix": setup.c.tolist(),
            "identified_on": [n for n, r in setup.roles.items() if r == "train"],
            "text": f"f = K q + C v over the {len(setup.coords)} coordinates (least squares on "
            "TRAIN); each coordinate's diagonal K_ii, C_ii is refitted with every candidate, the "
            "cross-coordinate terms stay fixed",
        },
        "mode": first["mode"],
        "mode_text": first["mode_text"],
        "coordinates": ranked,
        "rule": COORDINATE_RULE,
        "records": records,
        "notes": notes,
        "predictions": predictions,
        "diagnoses": diagnoses,
    }
