"""The one judging setup: the same inputs give the same judge in every command and env; the
reference is vetted before it judges; a model's own error is never a divergence."""

import json

import gymnasium as gym
import numpy as np
import pytest

import bushenv  # noqa: F401  (registers the envs)
from bushenv.cli import main
from bushenv.judge import JudgeError, build_judge
from bushenv.models import MODELS, BushingModel, ModelEntry, get_model
from bushenv.models.base import PAPER_DT
from bushenv.models.linear import TABLE1, LinearBushing
from bushenv.search.matrix import run_cell

FAST = ["--searchers", "random", "--budget", "8", "--max-shrink", "0", "--no-plots", "--quiet"]


class Oscillating(BushingModel):
    """A reference that rings by itself near rest: k x plus a 6 Hz force of 1 kN within 2 mm
    of rest (as a fitted hybrid that oscillates in its own holds does)."""

    name = "oscillating_test_reference"
    param_names = ()

    def __init__(self, dt: float = PAPER_DT) -> None:
        super().__init__(dt)

    @classmethod
    def preset(cls, axis="axial", dt=PAPER_DT):
        return cls(dt)

    @property
    def n_state(self) -> int:
        return 1

    def _advance(self, x, v, out):
        for t in range(x.shape[0]):
            self.state[0] += 1
            ring = 1e3 * np.sin(2 * np.pi * 6.0 * self.state[0] * self.dt) * (np.abs(x[t]) < 2e-3)
            out[t] = 3.8e5 * x[t] + ring

    def copy(self):
        return Oscillating(self.dt)


class Stiff(LinearBushing):
    """Another bushing: 3.2 times the Table-1 axial stiffness."""

    name = "stiff_test_reference"

    @classmethod
    def preset(cls, axis="axial", dt=PAPER_DT):
        t = TABLE1[axis]
        return cls(k_n_per_m=3.2 * t["k_n_per_m"], c_ns_per_m=t["c_ns_per_m"], dt=dt)


class Pulling(LinearBushing):
    """A reference that pulls where a bushing pushes back (negative stiffness)."""

    name = "pulling_test_reference"

    @classmethod
    def preset(cls, axis="axial", dt=PAPER_DT):
        t = TABLE1[axis]
        return cls(k_n_per_m=-t["k_n_per_m"], c_ns_per_m=t["c_ns_per_m"], dt=dt)


class Buggy(LinearBushing):
    """A model whose force has a numpy shape error after a few samples."""

    name = "buggy_test_model"

    @classmethod
    def preset(cls, axis="axial", dt=PAPER_DT):
        return cls(dt=dt, **TABLE1[axis])

    def _advance(self, x, v, out):
        if x.shape[0] > 3:
            np.ones(3) + np.ones(4)
        super()._advance(x, v, out)


@pytest.fixture
def registered():
    entries = {
        "osc": ModelEntry(Oscillating, "test: rings near rest"),
        "stiff": ModelEntry(Stiff, "test: another bushing"),
        "pulling": ModelEntry(Pulling, "test: wrong sign"),
        "buggy": ModelEntry(Buggy, "test: a model with a bug"),
    }
    from contextlib import ExitStack

    with ExitStack() as stack:
        for name, entry in entries.items():
            stack.enter_context(MODELS.temporarily(name, entry))
        yield


def test_the_same_inputs_give_the_same_judge_in_every_command_and_env(tmp_path, capsys):
    model = get_model("nn", axis="axial")
    want = build_judge("nn", "hybrid", axis="axial", dt=model.dt, model_object=model)
    # attack
    assert main(["attack", "--model", "nn", "--reference", "hybrid", *FAST,
                 "--out", str(tmp_path / "a")]) == 0  # fmt: skip
    attack = json.loads((tmp_path / "a" / "report.json").read_text())["judge"]
    # campaign (one cell)
    cell = {"model": "nn", "axis": "axial", "searcher": "random", "seed": 0, "budget": 4,
            "env": "rig", "reference": "hybrid"}  # fmt: skip
    campaign = run_cell(cell)["judge"]
    # certify
    main(["certify", "nn", "--reference", "hybrid", "--holds", "5", "--passivity-mm", "0",
          "--energy-mm", "1", "--quiet", "--out", str(tmp_path / "c")])  # fmt: skip
    certify = json.loads((tmp_path / "c" / "certificate.json").read_text())["judge"]
    want_json = json.loads(json.dumps(want.describe()))
    for got in (attack, campaign, certify):
        assert got == want_json
    # the env's judge: the same reference and vetting (the env compares nothing with the
    # reference, so its judge runs without the model: compatibility not run)
    env = gym.make("bushenv/BushRig-v0", model="nn", reference="hybrid")
    env_judge = env.unwrapped.params.judge
    assert env_judge.reference_spec == want.reference_spec
    assert env_judge.scales == want.scales and env_judge.criteria == want.criteria
    names = ["holds", "certificate holds", "records", "passivity", "compatibility"]  # a NARX one
    assert [c.name for c in env_judge.vetting.checks] == names


def test_a_reference_that_rings_by_itself_is_refused_naming_its_holds(registered, tmp_path, capsys):
    out = tmp_path / "a"
    code = main(["attack", "--model", "nn", "--reference", "osc", *FAST, "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert "the reference osc failed its vetting: holds:" in err[0]
    assert "oscillating between -1.88 and +1.88 mm" in err[0] and "--trust-reference" in err[0]
    assert not (out / "report.json").exists()


def test_trust_reference_judges_anyway_and_marks_every_verdict_unvetted(
    registered, tmp_path, capsys
):
    out = tmp_path / "a"
    argv = ["attack", "--model", "nn", "--reference", "osc", "--trust-reference", *FAST]
    assert main([*argv, "--out", str(out)]) == 0
    report = json.loads((out / "report.json").read_text())
    assert report["judge"]["unvetted"] and report["judge"]["trusted_by_flag"]
    assert any(n.startswith("UNVETTED REFERENCE: osc") for n in report["notes"])
    assert "verdicts UNVETTED" in capsys.readouterr().out


def test_a_reference_of_another_bushing_is_refused_when_the_model_has_records(tmp_path, capsys):
    from bushenv.machine import random_test
    from bushenv.records import save_csv
    from bushenv.reference.rubber import RubberBushing

    rec = random_test(RubberBushing.preset("axial", seed=3), 1.0, duration_s=8.0, seed=3)
    train = save_csv(rec, tmp_path / "train.csv")
    mine = tmp_path / "mine.npz"
    assert main(["fit", str(train), "--model", "linear", "--out", str(mine), "--quiet"]) == 0
    t = TABLE1["axial"]
    other = LinearBushing(k_n_per_m=3.2 * t["k_n_per_m"], c_ns_per_m=t["c_ns_per_m"])
    other = other.save(tmp_path / "other.npz")
    capsys.readouterr()
    argv = ["attack", "--model", str(mine), "--reference", str(other), *FAST]
    assert main([*argv, "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err
    assert "compatibility: RMS ratio on the model's card's records: train.csv" in err
    assert "beyond 30%" in err


def test_a_stiffer_reference_without_records_is_not_checked_and_not_passed(registered):
    model = get_model("nn", axis="axial")
    judge = build_judge("nn", "stiff", axis="axial", dt=model.dt, model_object=model)
    compat = {c.name: c for c in judge.vetting.checks}["compatibility"]
    assert compat.passed is None and compat.verdict == "not checked"
    assert compat.detail.startswith("undecided:") and "give the model under test" in compat.detail
    assert "a factor 3.1" in compat.detail or "a factor 3.2" in compat.detail
    # judged, not refused, and never "passed" beside it
    assert judge.vetting.passed and judge.vetting.verdict == "not fully checked"
    assert "not checked: records, compatibility" in judge.vetting.headline()


def test_a_reference_that_pulls_is_refused_for_its_wrong_sign(registered):
    model = get_model("nn", axis="axial")
    msg = r"pulling failed its vetting: scales: .* static stiffness is -3"
    with pytest.raises(JudgeError, match=msg):
        build_judge("nn", "pulling", axis="axial", dt=model.dt, model_object=model)


def test_none_means_no_reference_in_attack_and_campaign(tmp_path, capsys):
    out = tmp_path / "a"
    assert main(["attack", "--model", "nn", "--reference", "none", *FAST, "--out", str(out)]) == 0
    report = json.loads((out / "report.json").read_text())
    assert report["judge"]["reference"] is None
    assert (
        "deviation" not in report["criteria"]["run"] and "static" not in report["criteria"]["run"]
    )
    m = tmp_path / "m"
    argv = ["campaign", "--models", "nn", "--searchers", "random", "--seeds", "0", "--budget", "4"]
    assert main([*argv, "--reference", "none", "--workers", "1", "--out", str(m)]) == 0
    row = json.loads((m / "cells.jsonl").read_text().splitlines()[0])
    assert row["reference"] == "none" and row["judge"]["reference"] is None
    assert row["judge"]["criteria"] == report["judge"]["criteria"]


def test_a_model_that_raises_is_a_model_error_with_its_message_not_a_divergence(
    registered, tmp_path, capsys
):
    out = tmp_path / "a"
    assert main(["attack", "--model", "buggy", *FAST, "--out", str(out)]) == 3
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("bushenv attack: model error: buggy_test_model:")
    assert "operands could not be broadcast" in err[0] and "not a divergence" in err[0]


def test_the_default_attack_targets_the_papers_nn_with_the_papers_hybrid_and_the_certified():
    from bushenv.search.campaign import CampaignConfig
    from bushenv.search.campaign_models import roles

    config = CampaignConfig().checked()
    judge = build_judge(config.model, None, axis="axial", dt=PAPER_DT)
    got = roles(config, judge, [])
    assert got == [("target", "nn-paper"), ("hybrid", "hybrid-paper"), ("control", "linear"),
                   ("also", "nn"), ("also", "hybrid")]  # fmt: skip


def test_every_hold_the_certificate_lists_is_confirmed_or_refuted_by_the_attack(tmp_path):
    out = tmp_path / "a"
    argv = ["attack", "--model", "nn-paper", "--axis", "radial", *FAST, "--out", str(out)]
    assert main(argv) == 0
    report = json.loads((out / "report.json").read_text())
    stage = report["hold_stage"]
    assert stage["run"] and stage["listed"] == len(stage["holds"]) > 0
    confirmed = [h for h in stage["holds"] if h["confirmed"]]
    assert confirmed  # the radial papers' NN holds wrong-sign forces the judge confirms
    holds = report["models"]["nn-paper"]["searchers"]["cert-holds"]
    assert holds["n_failures"] == len(confirmed)
    # and they are among the failures the hybrid and the control are rechecked on
    assert report["recheck"]["profiles"] >= len(confirmed)


def test_every_saved_case_records_the_judge_of_its_report(tmp_path):
    out, corpus = tmp_path / "a", tmp_path / "corp"
    argv = ["attack", "--model", "nn-paper", "--searchers", "random", "--budget", "8"]
    argv += ["--max-shrink", "1", "--shrink-budget", "20", "--no-plots", "--quiet", "--save"]
    assert main([*argv, "--corpus", str(corpus), "--out", str(out)]) == 0
    report = json.loads((out / "report.json").read_text())
    cases = sorted(corpus.glob("*.json"))
    assert cases
    for path in cases:
        assert json.loads(path.read_text())["judge"] == report["judge"]


def test_rl_searchers_attack_a_model_file_without_a_reference(tmp_path, capsys):
    # the agent's rig runs the model beside itself; the judge (no reference) is the
    # evaluator's, so the env must not vet the model as if it were a reference
    k = TABLE1["axial"]
    mine = LinearBushing(k_n_per_m=-0.05 * k["k_n_per_m"], c_ns_per_m=k["c_ns_per_m"])
    path = mine.save(tmp_path / "pulling.npz")
    argv = ["attack", "--model", str(path), "--searchers", "ppo", "--budget", "4"]
    argv += ["--rl-budget", "4", "--max-shrink", "0", "--no-plots", "--quiet", "--stroke-mm", "3"]
    assert main([*argv, "--out", str(tmp_path / "a")]) == 0


def test_the_envelope_is_the_reference_cards_records_and_a_failure_says_if_it_left_it(tmp_path):
    from bushenv.machine import random_test
    from bushenv.records import save_csv
    from bushenv.reference.rubber import RubberBushing

    rec = random_test(RubberBushing.preset("axial", seed=3), 1.0, duration_s=8.0, seed=3)
    train = save_csv(rec, tmp_path / "train.csv")
    ref = tmp_path / "ref.npz"
    assert main(["fit", str(train), "--model", "linear", "--out", str(ref), "--quiet"]) == 0
    model = get_model("nn", axis="axial")
    judge = build_judge("nn", str(ref), axis="axial", dt=model.dt, model_object=model)
    peak = float(np.max(np.abs(rec.displacement)))
    x_max, v_max, source = judge.envelope
    assert x_max == pytest.approx(peak) and "card's training records" in source
    slow = np.linspace(0.0, 0.9 * peak, 400)
    assert judge.in_envelope(slow, model.dt) is True
    assert judge.in_envelope(1.2 / 0.9 * slow, model.dt) is False  # beyond the records' peak
    jump = np.array([0.0, 0.9 * peak])  # within the stroke, faster than the records went
    assert judge.in_envelope(jump, model.dt) is False


def test_missing_records_are_not_checked_naming_them_and_the_headline_is_not_passed(tmp_path):
    from bushenv.machine import random_test
    from bushenv.records import save_csv
    from bushenv.reference.rubber import RubberBushing
    from bushenv.search.campaign_report import format_table

    rec = random_test(RubberBushing.preset("axial", seed=3), 1.0, duration_s=8.0, seed=3)
    train = save_csv(rec, tmp_path / "train.csv")
    ref = tmp_path / "ref.npz"
    assert main(["fit", str(train), "--model", "linear", "--out", str(ref), "--quiet"]) == 0
    model = get_model("nn", axis="axial")
    judge = build_judge("nn", str(ref), axis="axial", dt=model.dt, model_object=model)
    assert {c.name: c.verdict for c in judge.vetting.checks}["records"] == "pass"
    assert judge.vetting.verdict == "passed" and judge.vetting.complete
    train.unlink()  # the card's records are gone
    judge = build_judge("nn", str(ref), axis="axial", dt=model.dt, model_object=model)
    records = {c.name: c for c in judge.vetting.checks}["records"]
    assert records.verdict == "not checked" and "train.csv" in records.detail
    assert f"put the record files beside {tmp_path}" in records.detail
    assert judge.vetting.passed and judge.vetting.verdict == "not fully checked"
    # the report's headline says so, never "passed" beside a check that did not pass
    report = {"reference": {"spec": str(ref)}, "criteria": {"run": []}, "models": {},
              "judge": json.loads(json.dumps(judge.describe()))}  # fmt: skip
    text = format_table(report, "nn")
    assert "vetted, not fully checked: 3 of 4 passed, not checked: records" in text
    assert "  records: not checked (its own card's records (train.csv) are not there" in text
    assert "vetted, passed" not in text


def test_a_trusted_reference_that_rings_marks_the_verdicts_where_it_rings(tmp_path):
    from certify.conftest import ringing_hybrid

    ring = ringing_hybrid().save(tmp_path / "ring.npz")
    t = TABLE1["axial"]
    pulls = LinearBushing(k_n_per_m=-t["k_n_per_m"], c_ns_per_m=t["c_ns_per_m"])
    pulls = pulls.save(tmp_path / "pulls.npz")
    argv = ["attack", "--model", str(pulls), "--reference", str(ring), "--stroke-mm", "2", *FAST]
    assert main([*argv, "--out", str(tmp_path / "refused")]) == 2
    assert main([*argv, "--trust-reference", "--out", str(tmp_path / "a")]) == 0
    report = json.loads((tmp_path / "a" / "report.json").read_text())
    (lo, hi),  = report["judge"]["unvetted_ranges_m"]  # fmt: skip
    assert lo < -1.25e-3 < hi and report["judge"]["vetting_verdict"] == "FAILED"
    row = report["models"]["pulls"]["searchers"]["random"]
    assert row["diverged"] and 0 < row["failures_in_unvetted_range"] < row["n_failures"]
    assert row["first_failure"]["reference_unvetted_here"] in (True, False)
