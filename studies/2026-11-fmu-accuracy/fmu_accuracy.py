"""How closely exported FMUs, run in FMPy, give bushenv's forces: studies/2026-11-fmu-accuracy/README.md.

    python studies/2026-11-fmu-accuracy/fmu_accuracy.py            # ~1.5 min on the shared 2 cores

Every error is max |F_fmu - F_bushenv| over the peak |F_bushenv| of the run, worst over the
inputs (a random n = 1 record of 10 s, a 4 mm step held 1.5 s, two sines). Masters:
``simulate_fmu`` (FMPy's own: reads outputs after doStep, before the next input), the
set-then-read master (``tests/export/fmu_masters.py``), FMI 2 input derivatives.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np
from fmpy import simulate_fmu

from bushenv import excitation as ex
from bushenv.export import export_fmu
from bushenv.models import PAPER_DT, get_model
from bushenv.models.boucwen import BoucWenBushing

# The FMPy masters and the converged Bouc-Wen run of the export tests.
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests" / "export"))
from fmu_masters import converged, derivatives_then_step, set_then_read  # noqa: E402

DT = PAPER_DT
AXIS = {"linear": "axial", "nn": "axial", "hybrid": "axial", "boucwen": "radial"}
INPUTS = {
    "random n=1": ex.random_rpc(1.0, 10.0, DT, seed=0),
    "4 mm step": ex.step_hold(4e-3, 1.5, DT),
    "sines": ex.sine(2.0, 3e-3, 2.0, DT) + ex.sine(23.0, 0.4e-3, 2.0, DT),
}


def _signal(has_v, t, x, v):
    names = [("time", float), ("deflection", float)] + ([("velocity", float)] if has_v else [])
    cols = [t, x] + ([v] if has_v else [])
    return np.array(list(zip(*cols, strict=True)), dtype=names)


def _rel(a, b, peak):
    return float(np.max(np.abs(a - b)) / peak)


def _latest_known(tc: np.ndarray) -> np.ndarray:
    """Index of the latest sample at or before the previous communication point (what a
    master that reads before it sets the next input can get), for each point but the first."""
    return np.floor(tc[:-1] / DT + 1e-6).astype(int)


def errors(path: Path, model) -> tuple[dict[str, float], dict[tuple[str, str], float]]:
    """(exactness: worst over INPUTS per master, cost: per master and input); see the module
    docstring and docs/export.md."""
    has_v = model.name != "nn"
    exact: dict[str, float] = {}
    cost: dict[tuple[str, str], float] = {}
    rng = np.random.default_rng(0)
    for label, x in INPUTS.items():
        v = np.gradient(x, DT)
        t = np.arange(len(x)) * DT
        ref = model.simulate(x, v)
        peak = float(np.max(np.abs(ref)))
        row = {}
        sig = _signal(has_v, t, x, v)
        res = simulate_fmu(
            str(path), stop_time=t[-1], output_interval=DT, input=sig, output=["force"]
        )
        row["simulate_fmu h = dt, vs F_(k-1)"] = _rel(res["force"][1:], ref[:-1], peak)
        cost[("simulate_fmu h = dt, vs F_k (the lag)", label)] = _rel(
            res["force"][1:], ref[1:], peak
        )
        for k in (0.25, 2.5):
            res = simulate_fmu(
                str(path), stop_time=t[-1], output_interval=k * DT, input=sig, output=["force"]
            )
            tc, n = res["time"], _latest_known(res["time"])
            ts = np.arange(n[-1] + 1) * DT
            seen = model.simulate(*(np.interp(ts, tc, np.interp(tc, t, a)) for a in (x, v)))
            row[f"simulate_fmu h = {k} dt, vs F on the interpolated input"] = _rel(
                res["force"][1:], seen[n], peak
            )
            if k > 1:
                cost[(f"simulate_fmu h = {k} dt, vs F (interpolation)", label)] = _rel(
                    res["force"][1:], ref[n], peak
                )
        row["set-then-read h = dt"] = _rel(set_then_read(path, t, x, v), ref, peak)
        tc = np.concatenate([[0.0], np.cumsum(rng.uniform(0.3, 3.7, 2 * len(x)) * DT)])
        tc = tc[tc <= t[-1]]
        xc, vc = np.interp(tc, t, x), np.interp(tc, t, v)
        got = set_then_read(path, tc, xc, vc)
        n = np.floor(tc / DT + 1e-6).astype(int)
        ts = np.arange(n[-1] + 1) * DT
        seen = model.simulate(np.interp(ts, tc, xc), np.interp(ts, tc, vc))
        row["set-then-read random h in [0.3, 3.7] dt, vs F on the interpolated input"] = _rel(
            got, seen[n], peak
        )
        cost[("set-then-read random h in [0.3, 3.7] dt, vs F (interpolation)", label)] = _rel(
            got, ref[n], peak
        )
        if path.name.endswith("2.0.fmu"):
            got = derivatives_then_step(path, t, x, v)
            row["FMI 2 input derivatives h = dt, read before the next input"] = _rel(
                got, ref[1:], peak
            )
        for key, val in row.items():
            exact[key] = max(exact.get(key, 0.0), val)
    return exact, cost


def programme_table(paths: dict[str, Path]) -> None:
    """The papers' programme (bushenv.programmes.papers_programme: harmonic grid, n = 1 and
    n = 1.5 records, 4 mm step held 10 s; 28 records, 65,638 samples) at h = dt."""
    from bushenv.programmes import papers_programme

    items = papers_programme(DT)
    print("\n| FMU | simulate_fmu h = dt, vs F one step earlier | set-then-read h = dt |")
    print("|---|---:|---:|")
    for label, path in paths.items():
        model = get_model(label.split()[0], axis=AXIS[label.split()[0]])
        w = [0.0, 0.0]
        for item in items:
            x = item.x
            v = np.gradient(x, DT)
            t = np.arange(len(x)) * DT
            ref = model.simulate(x, v)
            peak = float(np.max(np.abs(ref)))
            res = simulate_fmu(
                str(path),
                stop_time=t[-1],
                output_interval=DT,
                input=_signal(model.name != "nn", t, x, v),
                output=["force"],
            )
            w[0] = max(w[0], _rel(res["force"][1:], ref[:-1], peak))
            w[1] = max(w[1], _rel(set_then_read(path, t, x, v), ref, peak))
        print(f"| {label} | {w[0]:.2g} | {w[1]:.2g} |", flush=True)


def boucwen_table(folder: Path) -> None:
    """The C's RK4 against the converged reference and against bushenv's kernel."""
    sets = {
        "shipped axial": get_model("boucwen", axis="axial"),
        "shipped radial": get_model("boucwen", axis="radial"),
        "Table 3 (seed 002)": BoucWenBushing.preset(),
    }
    print("\n| parameter set | sub-steps | C vs converged | bushenv vs converged | C vs bushenv |")
    print("|---|---:|---:|---:|---:|")
    for name, model in sets.items():
        for n_sub in (32, 128):
            path = export_fmu(model, folder / f"bw{n_sub}.fmu", "2.0", substeps=n_sub).path
            w = [0.0, 0.0, 0.0]
            for x in INPUTS.values():
                v = np.gradient(x, DT)
                t = np.arange(len(x)) * DT
                ref = converged(model.vector()[:, None], x[:, None], v[:, None])[:, 0]
                mine = model.simulate(x, v)
                got = set_then_read(path, t, x, v)
                peak = float(np.max(np.abs(ref)))
                for i, (a, b) in enumerate(((got, ref), (mine, ref), (got, mine))):
                    w[i] = max(w[i], _rel(a, b, peak))
            print(f"| {name} | {n_sub} | {w[0]:.2g} | {w[1]:.2g} | {w[2]:.2g} |", flush=True)


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        table: dict[str, dict[str, float]] = {}
        paths: dict[str, Path] = {}
        costs: dict[str, dict[tuple[str, str], float]] = {}
        for name in ("linear", "nn", "hybrid", "boucwen"):
            model = get_model(name, axis=AXIS[name])
            for version in ("2.0", "3.0"):
                path = export_fmu(model, folder / f"{name}-{version}.fmu", version).path
                paths[f"{name} FMI {version}"] = path
                table[f"{name} FMI {version}"], cost = errors(path, model)
                if version == "2.0":  # the same numbers in 3.0 (one C core)
                    costs[name] = cost
                print(f"  measured {name} FMI {version}", file=sys.stderr, flush=True)
        cases = list(next(iter(table.values())))
        print("| master, step | " + " | ".join(table) + " |")
        print("|---|" + "---:|" * len(table))
        for case in cases:
            cells = [f"{row[case]:.2g}" if case in row else "" for row in table.values()]
            print(f"| {case} | " + " | ".join(cells) + " |")
        keys = list(next(iter(costs.values())))
        print("\n| master, step | input | " + " | ".join(costs) + " |")
        print("|---|---|" + "---:|" * len(costs))
        for case, label in keys:
            cells = [f"{c[(case, label)]:.2g}" for c in costs.values()]
            print(f"| {case} | {label} | " + " | ".join(cells) + " |")
        programme_table(paths)
        boucwen_table(folder)
    return 0


if __name__ == "__main__":
    sys.exit(main())
