"""``scripts/bench.py --quick --only fmu`` produces the FMU step figures (speed targets are the
benchmark's full run, never a unit test)."""

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FIGURES = (
    "bushenv_step",
    "fmpy_step",
    "fmpy_over_bushenv",
    "c_model_step",
    "c_fmi_step",
    "c_fmi_over_bushenv",
)

pytest.importorskip("fmpy")


def test_quick_fmu_benchmark_produces_its_figures(tmp_path):
    out = tmp_path / "bench.json"
    proc = subprocess.run(
        [
            sys.executable,
            str(ROOT / "scripts" / "bench.py"),
            "--quick",
            "--only",
            "fmu",
            "--json",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    rows = {r["name"]: r for r in json.loads(out.read_text())["figures"]}
    for name in FIGURES:
        r = rows[f"fmu.nn.{name}"]
        assert math.isfinite(r["value"]) and r["value"] > 0 and r["unit"], name
    assert rows["fmu.nn.fmpy_over_bushenv"]["target"] == 10.0
    assert rows["fmu.nn.c_fmi_over_bushenv"]["target"] == 2.0
