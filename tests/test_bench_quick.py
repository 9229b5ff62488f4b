"""``scripts/bench.py --quick``: the CI version of the benchmark produces every figure.

Only that each figure is produced (finite, with its unit, and ``met`` wherever a target is
set) is checked: speed targets belong to the benchmark's full run, never to a unit test.
"""

import importlib.util
import json
import math
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

EXPECTED = [
    *(
        f"free_run.{m}.B{b}"
        for m in ("linear", "nn", "hybrid", "boucwen", "rubber")
        for b in (1, 64, 1024)
    ),
    "free_run.nn.B1024.threads2",
    "free_run.boucwen.B1024.threads2",
    "free_run.boucwen.error_vs_converged",
    "free_run.boucwen.trial_steps_per_sample",
    "compare.boucwen.bushenv_B1",
    "compare.boucwen.bushenv_B1.error_vs_converged",
    *(
        f"compare.boucwen.{f}_{m}"
        for f in ("scipy", "bushenv_B1_over_scipy")
        for m in ("LSODA", "Radau")
    ),
    "compare.nn.torch_agreement",
    *(
        f"compare.nn.{f}.threads{t}"
        for f in ("torch", "bushenv", "bushenv_over_torch")
        for t in (1, 2)
    ),
    *(
        f"free_run.{m}.{f}"
        for m in ("nn", "hybrid")
        for f in (
            "float32_error",
            "float32_error_numpy",
            "B1024.float32",
            "B1024.threads2.float32",
        )
    ),
    *(f"step_latency.{m}" for m in ("linear", "nn", "hybrid", "boucwen", "rubber")),
    "env.CartPole-v1.single",
    "env.CartPole-v1.vector1024",
    "env.BushRig-v0.nn.single_us_over_cartpole_us",
    "env.BushRig-v0.nn.vector1024_speedup_vs_cartpole_single",
    "env.QuarterCar-v0.nn.single",
    "verification_6.44s.nn",
    "verification_6.44s.boucwen",
    "identification.nn",
    "identification.boucwen",
    *(
        f"identification.{m}.rms_ratio_{k}"
        for m in ("noise_floor", "nn", "boucwen")
        for k in ("unseen_same_amplitude", "unseen_n1.5")
    ),
    *(
        f"fit_command.{m}{k}"
        for m in ("nn", "nn-choose-off", "hybrid", "boucwen")
        for k in ("", ".rms_ratio_unseen_n1")
    ),
    "fit_command.nn.time_ratio_choice_vs_choose_off",
    "campaign.random.threads2.evaluations_per_s",
    "campaign.nn.random.seconds_to_first_divergence",
    "campaign.nn.float32_verdict_changes",
    "attack.reference_boucwen_over_rubber.time_ratio",
    "attack.reference_boucwen_over_rubber.nn_searches_ratio",
    "attack.default.seconds",
    "memory.batch_B1024_T512.peak",
    "records.load_csv_20k_over_loadtxt",
    "diagnose.cross.4_records.seconds",
    "diagnose.3khz.4_records.seconds",
    "diagnose.3khz_halves.4_records.seconds",
    *(
        f"planar.{f}"
        for f in (
            "BushRig-v0.linear.single",
            "BushRig3-v0.linear.single",
            "BushRig3-v0.linear.step_time_over_bushrig",
            "BushRig3-v0.nn.step_time_over_bushrig",
            "free_run.nn.B1024",
            "free_run.nn.B1024.per_axis_over_one_axis",
            "QuarterCar-v0.linear.vector256.step_time_over_axes",
            "QuarterCar-v0.reference.vector256.step_time_over_axes",
        )
    ),
]


def test_quick_benchmark_produces_every_figure_with_units_and_targets(tmp_path):
    out = tmp_path / "bench.json"
    md = tmp_path / "bench.md"
    proc = subprocess.run(
        [
            sys.executable,
            str(ROOT / "scripts" / "bench.py"),
            "--quick",
            "--json",
            str(out),
            "--markdown",
            str(md),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    rows = {r["name"]: r for r in json.loads(out.read_text())["figures"]}
    missing = [n for n in EXPECTED if n not in rows]
    assert not missing, f"figures not produced: {missing}"
    for name, r in rows.items():
        assert r["unit"], name
        assert math.isfinite(r["value"]), f"{name} = {r['value']}"
        if "target" in r:
            assert isinstance(r["met"], bool), name
    assert rows["free_run.nn.B1024.threads2"]["target"] == 50e6
    assert rows["free_run.boucwen.B1024.threads2"]["target"] == 10e6
    assert rows["attack.reference_boucwen_over_rubber.time_ratio"]["target"] == 2.0
    # the comparisons are of the same computation: same network, same accuracy
    assert rows["compare.nn.torch_agreement"]["value"] < 1e-9
    for m in ("LSODA", "Radau"):
        assert rows[f"compare.boucwen.scipy_{m}"]["note"].startswith("rtol")
    assert "| verification_6.44s.nn |" in md.read_text()


def test_quick_certify_benchmark_produces_its_figures(tmp_path):
    out = tmp_path / "bench.json"
    docs = {p: p.read_bytes() for p in (ROOT / "docs").glob("benchmarks*.md")}
    proc = subprocess.run(
        [
            sys.executable,
            str(ROOT / "scripts" / "bench.py"),
            "--quick",
            "--only",
            "certify",
            "--json",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    rows = {r["name"]: r for r in json.loads(out.read_text())["figures"]}
    for name in ("nn", "hybrid"):
        for axis in ("axial", "radial"):
            r = rows[f"certify.{name}.{axis}.holds20"]
            assert r["unit"] == "s" and r["target"] == 1.0 and isinstance(r["met"], bool)
            assert math.isfinite(rows[f"certify.{name}.{axis}.analysis_holds20"]["value"])
    # --json writes the JSON only: the checkout's docs are written only when asked
    assert {p: p.read_bytes() for p in (ROOT / "docs").glob("benchmarks*.md")} == docs


def test_the_benchmarks_page_is_the_render_of_its_run_and_not_edited_by_hand(tmp_path):
    spec = importlib.util.spec_from_file_location("bench", ROOT / "scripts" / "bench.py")
    bench = importlib.util.module_from_spec(spec)
    sys.path.insert(0, str(ROOT / "scripts"))  # bench imports its sibling modules
    try:
        spec.loader.exec_module(bench)
    finally:
        sys.path.remove(str(ROOT / "scripts"))
    run = json.loads((ROOT / "docs" / "benchmarks.json").read_text())
    assert (ROOT / "docs" / "benchmarks.md").read_text() == bench.markdown(run), (
        "docs/benchmarks.md differs from its run: python scripts/bench.py --from-json "
        "docs/benchmarks.json --write-docs"
    )
    md = tmp_path / "page.md"
    assert (
        bench.main(["--from-json", str(ROOT / "docs" / "benchmarks.json"), "--markdown", str(md)])
        == 0
    )
    assert md.read_text() == bench.markdown(run)
