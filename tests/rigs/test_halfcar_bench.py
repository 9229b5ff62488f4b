"""``scripts/bench.py --quick --only halfcar``: the half car's figures are produced (speed
targets belong to the benchmark's full run, never to a unit test)."""

import json
import math
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
FIGURES = (
    "halfcar.HalfCar-v0.single",
    "halfcar.QuarterCar-v0.single",
    "halfcar.HalfCar-v0.step_time_over_quartercar",
    "halfcar.batch.B64",
    "halfcar.batch.B64_speedup_vs_single",
    "halfcar.batch.B64.threads2",
    "halfcar.batch.B64.threads2_speedup_vs_single",
)


def test_the_quick_benchmark_produces_the_half_cars_figures(tmp_path):
    out = tmp_path / "bench.json"
    proc = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "bench.py"), "--quick", "--only", "halfcar",
         "--json", str(out)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    rows = {r["name"]: r for r in json.loads(out.read_text())["figures"]}
    for name in FIGURES:
        assert name in rows, name
        assert rows[name]["unit"] and math.isfinite(rows[name]["value"]) and rows[name]["value"] > 0
