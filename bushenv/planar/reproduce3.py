"""The 3-axis table beside seed 000 Table 3: planar models identified on random motion of all
axes, judged free-running on unseen coupled records (``bushenv reproduce --planar``).

1. The planar reference (with its load cell) is driven by random motion at n = 1 on all axes,
   independent and correlated (``identification_s`` each, ``seed``), and (``identification=
   "programme"``, the default) by the coupled sine sets at n = 1 (a 2 mm radial preload under
   a rotation sweep, the reverse, and a 2 mm axial preload under a radial sweep,
   ``identification_s`` / 2 each), as ``bushenv measure
   --axes 3`` records them: the identification records. ``"random"`` leaves the sets out, as
   seed 000 identified on random motion only; then nothing in the records holds a deflection
   and a fit cannot tell its slow relaxation from its static stiffness (its card says so).
2. ``linear`` (3x3 K, C), ``nn-axis`` (the seeds' kind: three single-axis networks, seed 000
   §4.2), ``hybrid`` (3x3 backbone + MIMO network), ``boucwen`` (vector Bouc-Wen) and
   ``hybrid-bw`` (vector Bouc-Wen backbone + MIMO network) are identified on them
   (``bushenv.planar.fitting``, default options but no wall-clock limit on a search, so the
   table does not depend on the machine's load).
3. Each runs free on records it never saw, measured with other noise seeds: random motion
   with the axes correlated (one common drive, weight 0.8) at n = 1 and at n = 1.5, random
   independent at n = 1.5, and the coupled sine sets (a 3 mm radial preload under a rotation
   sweep, a rotation preload under a radial sweep, a 3 mm axial preload under a radial
   sweep). RMS ratio (seed 000 eq. 8), ESR (eq. 9) and MAX (largest error over the largest
   measured |f|, as Table 3) per axis.

Seed 000 Table 3's "NN" is the per-axis kind, so its rows sit beside ``nn-axis``. Where an
axis is at rest (the axial force of the radial and rotation sets, the moment of the axial
set), its force is load-cell noise only and the table gives the largest force the model
invents there, in N (N m).

``planar.json`` layout: {"settings": {...}, "paper": TABLE3, "records": {record: {model:
{axis: {"rms_ratio", "esr", "max_error_ratio", "max_error", "at_rest"}}}}, "identification_s":
{model: s}, "fit_notes": {model: [what its fit warned of, and whether a hybrid kept its
network]}}; fractions, N and N m.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from bushenv.identify.options import option_fields
from bushenv.metrics import esr, max_error, max_error_ratio, rms_ratio
from bushenv.models.planar_base import COORDS
from bushenv.planar.fitting import fit_planar, options_class
from bushenv.planar.machine import IDENTIFICATIONS, N_VERIFY, coupled_sets
from bushenv.planar.programme import programme, random_correlated, random_independent
from bushenv.progress import Progress
from bushenv.reference.planar import PlanarRubber

MODELS = ("linear", "nn-axis", "hybrid", "boucwen", "hybrid-bw")
EFFORT = {"linear": 0.1, "nn-axis": 10.0, "hybrid": 15.0, "boucwen": 25.0, "hybrid-bw": 40.0}
TABLE3 = {  # seed 000 Table 3 (3-axes rig simulation): RMS ratio %, ESR %, MAX %
    "axial": {"linear": (10.9, 0.5, 24.9), "nn-axis": (5.2, 0.2, 9.3), "hybrid": (5.1, 0.2, 8.4)},
    "radial": {"linear": (5.1, 0.4, 20.7), "nn-axis": (3.0, 0.2, 8.3), "hybrid": (3.0, 0.2, 7.8)},
}


def identification_records(
    dt: float, seed: int, ident_s: float, identification: str = "programme"
) -> list:
    """[(q, f)] of random motion at n = 1, independent and correlated, then (``"programme"``)
    the coupled sine sets at n = 1 of ``ident_s`` / 2 each; each record its noise seed."""
    if identification not in IDENTIFICATIONS:
        raise ValueError(f"identification {identification!r}; known: {', '.join(IDENTIFICATIONS)}")
    motions = [drive(1.0, ident_s, dt, seed) for drive in (random_independent, random_correlated)]
    if identification == "programme":
        motions += [q for _, q in coupled_sets(1.0, dt, ident_s / 2)]
    return [
        (q, PlanarRubber.preset(seed=seed + 50 * k, dt=dt).simulate(q))
        for k, q in enumerate(motions)
    ]


def unseen_records(dt: float, seed: int, verif_s: float) -> dict[str, np.ndarray]:
    """The coupled records the models never saw, (T, 3) each, by name: ``programme``'s, but
    the random independent one at n = 1, with the verification amplitude in the names."""
    rec = programme(dt, seed, N_VERIFY, verif_s)
    shown = f"n={N_VERIFY:g}"
    return {
        "random correlated n=1": rec["random correlated n=1"],
        f"random correlated {shown}": rec["random correlated"],
        f"random independent {shown}": rec["random independent"],
        **{k: q for k, q in rec.items() if not k.startswith("random")},
    }


def planar_table(
    seed: int,
    ident_s: float,
    verif_s: float,
    dt: float,
    progress: Progress | None = None,
    models: tuple[str, ...] | None = None,
    identification: str = "programme",
) -> dict[str, Any]:
    """Identify ``models`` (default ``MODELS``) on the reference's ``identification_records``,
    judge them on ``unseen_records``; the report."""
    models = MODELS if models is None else models
    progress = progress or Progress(quiet=True)
    progress.total = sum(EFFORT[m] for m in models)
    progress.done = 0
    histories = identification_records(dt, seed, ident_s, identification)
    n_sets = len(histories) - 2
    shown = f"2 x {ident_s:g} s of random motion" + (
        f" and the {n_sets} coupled sine sets, {ident_s / 2:g} s each" if n_sets else ""
    )
    fitted, seconds, warnings = {}, {}, {}
    for name in models:
        progress.say(f"[3-axis] identifying {name} on {shown}, n = 1")
        t0 = time.perf_counter()
        result = fit_planar(histories, name, _untimed(name), dt, seed)
        fitted[name] = result.model
        seconds[name] = time.perf_counter() - t0
        # what the fit says its records could not identify, and whether a hybrid kept its
        # network, as its card would
        warnings[name] = [
            f"{k}: {v}" for k, v in result.info.items() if "warning" in k or k == "network"
        ]
        progress.update(progress.done + EFFORT[name], f"[3-axis] {name} in {seconds[name]:.1f} s")
    out: dict[str, Any] = {}
    for k, (rec, qt) in enumerate(unseen_records(dt, seed, verif_s).items()):
        ft = PlanarRubber.preset(seed=seed + 101 + k, dt=dt).simulate(qt)
        out[rec] = {}
        for name, model in fitted.items():
            pred = model.simulate(qt)
            out[rec][name] = {
                c: {
                    "rms_ratio": rms_ratio(ft[:, i], pred[:, i]),
                    "esr": esr(ft[:, i], pred[:, i]),
                    "max_error_ratio": max_error_ratio(ft[:, i], pred[:, i]),
                    "max_error": max_error(ft[:, i], pred[:, i]),
                    "at_rest": bool(np.all(qt[:, i] == 0)),
                }
                for i, c in enumerate(COORDS)
            }
    return {
        "settings": {
            "seed": seed,
            "identification_record_s": ident_s,
            "identification": identification,
            "verification_record_s": verif_s,
            "dt_s": dt,
        },  # fmt: skip
        "paper": TABLE3,
        "identification_s": seconds,
        "fit_notes": {m: w for m, w in warnings.items() if w},
        "records": out,
    }


def _untimed(name: str) -> dict[str, float] | None:
    """Default options, but a search stopped by its budget, not by the clock: the table is
    then the same on a loaded machine (a 120 s limit cut the Bouc-Wen search there)."""
    fields = {f.name for f in option_fields(options_class(name))}
    return {"time_limit_s": 0.0} if "time_limit_s" in fields else None


def format_planar(report: dict[str, Any]) -> str:
    """The table as text: per record and axis, RMS / MAX % for each model, Table 3 beside."""
    records = report["records"]
    models = list(next(iter(records.values())))
    head = f"{'record':32s} {'axis':9s}" + "".join(f"{m + ' RMS/MAX %':>22s}" for m in models)
    what = IDENTIFICATIONS[report["settings"].get("identification", "random")]
    lines = [
        f"3-axis table (seed 000 Table 3 beside): planar models identified on {what},",
        "free run on unseen coupled records; RMS ratio / MAX (% of max |f|)",
        head,
    ]
    for rec, row in records.items():
        for c in COORDS:
            cells = []
            for m in models:
                r = row[m][c]
                if r["at_rest"]:
                    unit = "N m" if c == "rotation" else "N"
                    cells.append(f"at rest: {r['max_error']:.0f} {unit}".rjust(22))
                else:
                    cells.append(f"{100 * r['rms_ratio']:.1f} / {100 * r['max_error_ratio']:.1f}"
                                 .rjust(22))  # fmt: skip
            lines.append(f"{rec:32s} {c:9s}" + "".join(cells))
    for c, row in report["paper"].items():
        cells = [
            (f"{row[m][0]:.1f} / {row[m][2]:.1f}" if m in row else "-").rjust(22) for m in models
        ]
        lines.append(f"{'seed 000 Table 3':32s} {c:9s}" + "".join(cells))
    secs = ", ".join(f"{m} {s:.1f} s" for m, s in report["identification_s"].items())
    lines.append(f"identified in: {secs}")
    for m, said in report.get("fit_notes", {}).items():
        lines += [f"{m}: {w}" for w in said]
    return "\n".join(lines)
