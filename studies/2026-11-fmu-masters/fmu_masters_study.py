"""Exported FMUs in the masters people use: studies/2026-11-fmu-masters/README.md.

    python studies/2026-11-fmu-masters/fmu_masters_study.py     # ~3 min on the shared 2 cores

Part 1, the velocity: what a master that sets only the deflection got from the former FMUs
(velocity input left at 0), what it gets now (the FMU's own backward difference), and how far
that rule is from bushenv's ``simulate`` default (the central difference).

Part 2, the masters: the random n = 1 record (10 s) as the deflection only, at communication
steps h = dt and dt/10, through a set-then-read master, FMPy's ``simulate_fmu`` in
co-simulation and in model exchange, and libcosim (if ``libcosimpy`` imports; FMI 2). Each
force read at a communication point t is judged against bushenv's force (same velocity rule)
held over the sample that contains t: RMS error over the force's RMS, and the largest error at
the samples themselves over the peak. Model exchange is also judged against bushenv's forces
interpolated linearly between samples (its force is continuous between them).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

from bushenv import excitation as ex
from bushenv.export import export_fmu
from bushenv.models import PAPER_DT, get_model

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests" / "export"))
from fmu_masters import (  # noqa: E402
    AXIS,
    backward_velocity,
    fmpy_simulate,
    held,
    libcosim,
    set_then_read,
)

DT = PAPER_DT
KINDS = ("linear", "nn", "hybrid", "boucwen")
RECORDS = {
    "random n=1": ex.random_rpc(1.0, 10.0, DT, seed=0),
    "4 mm step": ex.step_hold(4e-3, 1.5, DT),
}


def rel_max(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def rel_rms(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2)))


def velocity_table(fmus) -> list[str]:
    rows = [
        "| kind | record | former FMU, deflection only (v = 0) | this FMU, deflection only, "
        "vs bushenv (backward v) | backward v vs central v (bushenv), max / RMS |",
        "|---|---|---:|---:|---:|",
    ]
    for kind in KINDS:
        model = get_model(kind, axis=AXIS[kind])
        for name, x in RECORDS.items():
            t = np.arange(len(x)) * DT
            central = model.simulate(x)
            backward = model.simulate(x, backward_velocity(x, DT))
            no_v = model.simulate(x, np.zeros_like(x))
            got = set_then_read(fmus[kind, "2.0"], t, x)
            rows.append(
                f"| {kind} | {name} | {rel_max(no_v, central):.2g} of peak "
                f"| {rel_max(got, backward):.2g} | {rel_max(backward, central):.2g} of peak / "
                f"{rel_rms(backward, central):.2g} of RMS |"
            )
    return rows


def masters_table(fmus) -> list[str]:
    x = RECORDS["random n=1"]
    t = np.arange(len(x)) * DT
    refs = {k: get_model(k, axis=AXIS[k]).simulate(x, backward_velocity(x, DT)) for k in KINDS}
    try:
        import libcosimpy  # noqa: F401

        with_libcosim = True
    except ImportError:
        with_libcosim = False

    def runs(kind, h):
        tc = np.arange(int(np.floor(t[-1] / h + 1e-6)) + 1) * h
        xc = np.interp(tc, t, x)
        got = set_then_read(fmus[kind, "2.0"], tc, xc)
        if not np.array_equal(got, set_then_read(fmus[kind, "3.0"], tc, xc)):
            print(f"note: {kind} FMI 2.0 and 3.0 differ set-then-read at h = {h}")
        yield "set-then-read (FMPy classes), CS", tc, got
        yield "FMPy `simulate_fmu`, CS", *fmpy_simulate(fmus[kind, "2.0"], t, x, h)
        yield (
            "FMPy `simulate_fmu`, ME (CVode)",
            *fmpy_simulate(fmus[kind, "2.0"], t, x, h, "ModelExchange"),
        )
        if with_libcosim:
            yield "libcosim 0.0.6 (libcosimpy), CS, FMI 2", *libcosim(fmus[kind, "2.0"], t, x, h)

    rows = [
        "| master, form | step | " + " | ".join(f"{k}: RMS / at samples" for k in KINDS) + " |",
        "|---|---|" + "---:|" * len(KINDS),
    ]
    table: dict[tuple[str, str], list[str]] = {}
    for kind in KINDS:
        ref = refs[kind]
        for label, h in (("dt", DT), ("dt/10", DT / 10)):
            for master, tc, f in runs(kind, h):
                want = held(ref, tc, DT)
                # at the samples: the points on one, or just after it (libcosim's whole
                # nanoseconds put its points up to 3e-3 dt after the samples they meet)
                frac = tc / DT - np.floor(tc / DT + 1e-6)
                on = (frac < 1e-2) & (tc > 0)
                at = np.max(np.abs(f[on] - want[on])) / np.max(np.abs(ref)) if on.any() else np.nan
                cell = f"{100 * rel_rms(f, want):.3g} % / {at:.2g}"
                table.setdefault((master, label), []).append(cell)
                if "ME" in master:  # also against the forces interpolated between samples
                    smooth = f"{100 * rel_rms(f, np.interp(tc, t, ref)):.3g} %"
                    table.setdefault((master + ", vs interpolated", label), []).append(smooth)
                print(kind, master, label, cell, flush=True)
    for (master, label), cells in table.items():
        rows.append(f"| {master} | {label} | " + " | ".join(cells) + " |")
    if not with_libcosim:
        rows.append("(libcosimpy not installed here: its rows are missing)")
    return rows


def smoother_rows(fmus) -> list[str]:
    """The step-then-read masters on the smoother sines of the export tests (2 Hz, 3 mm plus
    23 Hz, 0.4 mm; 10 s): RMS error against the held force, nn and hybrid."""
    x = ex.sine(2.0, 3e-3, 10.0, DT) + ex.sine(23.0, 0.4e-3, 10.0, DT)
    t = np.arange(len(x)) * DT
    rows = [
        "| kind | step | FMPy `simulate_fmu`, CS | libcosim, CS, FMI 2 |",
        "|---|---|---:|---:|",
    ]
    for kind in ("nn", "hybrid"):
        ref = get_model(kind, axis=AXIS[kind]).simulate(x, backward_velocity(x, DT))
        for label, h in (("dt", DT), ("dt/10", DT / 10)):
            cells = []
            for master in (fmpy_simulate, libcosim):
                try:
                    tc, f = master(fmus[kind, "2.0"], t, x, h)
                except ImportError:
                    cells.append("not installed")
                    continue
                cells.append(f"{100 * rel_rms(f, held(ref, tc, DT)):.3g} %")
            rows.append(f"| {kind} | {label} | {' | '.join(cells)} |")
    return rows


def main() -> None:
    with tempfile.TemporaryDirectory(prefix="bushenv-study-") as folder:
        fmus = {
            (k, v): export_fmu(k, Path(folder) / f"{k}-{v}.fmu", v, axis=AXIS[k]).path
            for k in KINDS
            for v in ("2.0", "3.0")
        }
        lines = ["## The velocity", "", *velocity_table(fmus), "", "## The masters", ""]
        lines += masters_table(fmus)
        lines += ["", "## Step-then-read on smoother sines", "", *smoother_rows(fmus)]
    print("\n".join(lines))


if __name__ == "__main__":
    main()
