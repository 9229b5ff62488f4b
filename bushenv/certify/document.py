"""The certificate's JSON document, one layout for any number of coordinates C.

Every hold, fold and passivity entry carries its deflection vector ``q`` and its forces as
vectors (N, or N m for a rotation); a one-coordinate certificate also carries the scalar forms
its files have always had (``x_m``, ``force_n``, ``static_force_n``, ``im_k_n_per_m``, ...), so
the certificates written before still read the same.
"""

from __future__ import annotations

import numpy as np

from bushenv.certify.holds import AVERAGE_S
from bushenv.certify.network import describe
from bushenv.certify.passivity import amplitudes, loss_eigenvalues, negative_bands
from bushenv.certify.stiffness import dynamic_stiffness, sine_stiffness
from bushenv.divergence import static_margin
from bushenv.scales import FORCE_FLOOR_N

# A sign is meaningful above 10 N: over 3 sigma of the reference rubber's load-cell noise
# (sigma <= 3 N, radial) and below the force of the smallest hold that matters (0.05 mm x
# 380 N/mm = 19 N, seed 000 Table 1).
WRONG_SIGN_N = 10.0
LEVER_M = 0.04  # metres per radian when a moment is weighed against a force (N m = N x 0.04 m)


def lever_of(units) -> np.ndarray:
    """(C,) 1 for a translation, ``LEVER_M`` for a rotation: a force floor's scale per
    coordinate (a moment's floor is the force's times the lever)."""
    return np.array([LEVER_M if u == "rad" else 1.0 for u in units])


def _vec(a) -> list[float] | None:
    return None if a is None else [float(v) for v in np.atleast_1d(a)]


def hold_entry(net, fp, gh, run, i, ref, bands, wrong_sign) -> dict:
    """One hold's entry: its fixed points, its free run, its static force against ``ref``
    (C,) (NaN: no reference) and the non-passive bands about the point its run reaches."""
    one = net.n_coords == 1
    idx, q = fp.of_hold(i), fp.q[i]
    static = None if run.reached is None else fp.force[idx[run.reached]]
    has_ref = bool(np.all(np.isfinite(ref)))
    wrong = static is not None and bool(
        wrong_sign(q[None], static[None], net.units, ref[None] if has_ref else None)[0]
    )
    floors = FORCE_FLOOR_N * lever_of(net.units)
    off = static is not None and has_ref and bool(np.any(static_margin(static, ref, floors) < 0))
    g = gh.hold == i
    entry = {
        "q": _vec(q),
        "fixed_points": [
            {
                "force": _vec(fp.force[p]),
                "spectral_radius": float(fp.spectral_radius[p]),
                "stable": bool(fp.stable[p]),
            }
            for p in idx
        ],
        "reached": run.reached,
        "departs": run.departs,
        "departure_s": run.departure_s,
        "departure_observed": run.observed if run.departs else None,
        "departs_from": run.departs_from,
        "linger_force": _vec(run.linger_force),
        "oscillates": run.oscillates,
        "static_force": _vec(static),
        "reference_static_force": _vec(ref) if has_ref else None,
        "static_error": None if static is None or not has_ref else _vec(static - ref),
        "wrong_sign": wrong,
        "static_off": off,
        "ghosts": [
            {"force": _vec(net.force_n(q[0], y)), "passage_s": float(s)}
            for y, s in zip(gh.y[g], gh.passage_s[g], strict=True)
        ],
        "non_passive_bands_hz": [list(b) for b in bands],
        "unresolved_cells": int(fp.unresolved[i]),
    }
    if one:  # the scalar forms of one coordinate
        entry["x_m"] = float(q[0])
        for p in entry["fixed_points"] + entry["ghosts"]:
            p["force_n"] = p["force"][0]
        for key in ("linger_force", "static_force", "reference_static_force", "static_error"):
            entry[f"{key}_n"] = None if entry[key] is None else entry[key][0]
    return entry


def passivity_entries(net, fp, reference, freq: np.ndarray, opts) -> list[dict]:
    """Per hold of ``fp`` (the passivity holds): the loss eigenvalues (least first, J) about
    each stable fixed point over ``freq``, and the reference's by sines of
    ``opts.reference_amplitude_m`` (rotations: the same fraction of their n = 1 peak)."""
    one = net.n_coords == 1
    d = amplitudes(net.units)
    ref_freq = np.array(opts.reference_freq_hz)
    entries = []
    for i in range(len(fp.q)):
        idx = [p for p in fp.of_hold(i) if fp.stable[p]]
        k = dynamic_stiffness(net, fp.q[fp.hold[idx]], fp.y[idx], freq, opts.velocity)
        eig = loss_eigenvalues(k, d)  # (P, F, C)
        if reference is None:
            k_ref = np.full((ref_freq.size, net.n_coords, net.n_coords), np.nan + 0j)
        else:
            amp = opts.reference_amplitude_m * d / d[0] if not one else opts.reference_amplitude_m
            k_ref = sine_stiffness(reference, fp.q[i], ref_freq, amp)[0]
        eig_ref = (
            loss_eigenvalues(k_ref, d)
            if reference is not None
            else np.full((ref_freq.size, net.n_coords), np.nan)
        )
        entry = {
            "q": _vec(fp.q[i]),
            "fixed_points": [
                {
                    "force": _vec(fp.force[p]),
                    "non_passive_bands_hz": [list(b) for b in negative_bands(freq, e[:, 0])],
                }
                for p, e in zip(idx, eig, strict=True)
            ],
            "frequency_hz": freq,
            "loss_eigenvalues_j": eig,
            "reference_frequency_hz": ref_freq,
            "reference_loss_eigenvalues_j": eig_ref,
            "reference_negative_bands_hz": [
                list(b) for b in negative_bands(ref_freq, eig_ref[:, 0])
            ],
        }
        if one:
            entry["x_m"] = float(fp.q[i, 0])
            for p in entry["fixed_points"]:
                p["force_n"] = p["force"][0]
            entry["im_k_n_per_m"], entry["re_k_n_per_m"] = k[:, :, 0, 0].imag, k[:, :, 0, 0].real
            entry["reference_im_k_n_per_m"] = k_ref[:, 0, 0].imag
            entry["reference_re_k_n_per_m"] = k_ref[:, 0, 0].real
        entries.append(entry)
    return entries


def _ranges(x: np.ndarray, mask: np.ndarray) -> list[list[float]]:
    """[[first x, last x], ...] of the runs of consecutive True in ``mask``."""
    out, start = [], None
    for k, m in enumerate(list(mask) + [False]):
        if m and start is None:
            start = k
        if not m and start is not None:
            out.append([float(x[start]), float(x[k - 1])])
            start = None
    return out


def _fold_entry(f, one: bool) -> dict:
    entry = {
        "q": list(f.q),
        "q_from": list(f.q_from),
        "q_to": list(f.q_to),
        "force": list(f.force),
        "from": f.count_from,
        "to": f.count_to,
        "pair_exists": "above" if f.exists_above else "below",
        "spectral_radii": list(f.radii),
    }
    if one:
        entry["x_m"], entry["force_n"] = f.x_m, f.force_n
    return entry


def _summary(holds: list[dict], fo: list, pas: list[dict], one: bool) -> dict:
    q = np.array([h["q"] for h in holds])
    wrong = np.array([h["wrong_sign"] for h in holds])
    off = np.array([h["static_off"] for h in holds])
    count = np.array([len(h["fixed_points"]) for h in holds])
    stable = np.array([sum(p["stable"] for p in h["fixed_points"]) for h in holds])
    stable_end = np.array(
        [
            h["reached"] is not None
            and h["fixed_points"][h["reached"]]["stable"]
            and not h["departs"]
            for h in holds
        ]
    )
    rho = [
        h["fixed_points"][h["reached"]]["spectral_radius"]
        for h in holds
        if h["reached"] is not None
    ]
    at_rest = [p for e in pas if not any(e["q"]) for p in e["fixed_points"]]
    non_passive = [e for e in pas if any(p["non_passive_bands_hz"] for p in e["fixed_points"])]
    no_stable_p = sum(1 for e in pas if not e["fixed_points"])
    least = [float(np.min(e["loss_eigenvalues_j"])) for e in pas if len(e["fixed_points"])]
    unresolved = int(sum(h["unresolved_cells"] for h in holds))
    summary = {
        "holds": len(holds),
        "holds_settling_stably": int(stable_end.sum()),
        "holds_with_more_than_one": int(np.sum(count > 1)),
        "holds_without_a_stable_one": int(np.sum(stable == 0)),
        "departing_holds": int(sum(h["departs"] for h in holds)),
        "departing_unexplained": int(
            sum(h["departs"] and h["departs_from"] is None for h in holds)
        ),
        "oscillating_holds": int(sum(h["oscillates"] for h in holds)),
        "wrong_sign_holds": int(wrong.sum()),
        "static_off_holds": int(off.sum()),
        "folds": len(fo),
        "max_reached_spectral_radius": max(rho) if rho else None,
        "unresolved_cells": unresolved,
        "non_passive_bands_hz_at_rest": [b for p in at_rest for b in p["non_passive_bands_hz"]],
        "passivity_holds": len(pas),
        "passivity_holds_without_a_stable_point": no_stable_p,
        "non_passive_holds": len(non_passive),
        "least_loss_eigenvalue_j": min(least) if least else None,
        # one force per hold, reached stably, of the right sign, no fold, and every root found
        "passes_holds": bool(
            not fo
            and stable_end.all()
            and not wrong.any()
            and np.all(count == 1)
            and unresolved == 0
        ),
        "passes_passivity": not non_passive and not no_stable_p,
    }
    if one:
        summary["wrong_sign_ranges_m"] = _ranges(q[:, 0], wrong)
        summary["static_off_ranges_m"] = _ranges(q[:, 0], off)
    else:
        summary["wrong_sign_at"] = q[wrong].tolist()
    return summary


def document(net, opts, holds, fo, pas, scan, timing, has_reference: bool) -> dict:
    """The whole certificate document (``certificate.json``)."""
    from bushenv.certify.options import per_coordinate

    one = net.n_coords == 1
    settings = {
        "holds": opts.holds,
        "span": [float(s) for s in opts.spans(net.n_coords)],
        "per_coordinate": per_coordinate(opts.holds, net.n_coords),
        "hold_s": opts.hold_s,
        "reference_average_s": AVERAGE_S,
        "velocity": opts.velocity,
        "sign_floor_n": WRONG_SIGN_N,
        "lever_m_per_rad": LEVER_M,
        "static_off": "outside the divergence criterion static's band about F_ref "
        f"(bushenv.divergence.static_margin, floor {FORCE_FLOOR_N} N, moments x the lever)",
        "reference_sine_amplitude_m": opts.reference_amplitude_m,
        "wrong_sign_against": "the reference's static force"
        if has_reference
        else "the deflection (no reference: a passive bushing's static force points away "
        f"from rest, q . f >= 0; wrong where q . f < -{WRONG_SIGN_N:g} N x (|q_translations| "
        f"+ {LEVER_M:g} m/rad |q_rotations|))",
        "energy_scan": "sines of one coordinate judged by the divergence criterion energy"
        if one
        else "not run: the judge's sines are of one coordinate; passivity is the matrix test",
    }
    if one:
        settings["stroke_m"] = settings["span"][0]
    return {
        "format": "bushenv-certificate",
        "coords": list(net.coords),
        "units": list(net.units),
        "model": describe(net),
        "settings": settings,
        "summary": _summary(holds, fo, pas, one),
        "holds": holds,
        "folds": [_fold_entry(f, one) for f in fo],
        "passivity": {"holds": pas, "energy_scan": scan},
        "timing_s": timing,
    }
