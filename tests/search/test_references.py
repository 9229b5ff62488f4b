"""The reference is explicit: the static criterion, judging without a reference, the bushing's
own scales, and regression cases that remember what they were judged against."""

import json

import numpy as np
import pytest

from bushenv import excitation as ex
from bushenv.cli import main
from bushenv.divergence import judge
from bushenv.models.base import PAPER_DT as DT
from bushenv.models.hybrid import HybridBushing
from bushenv.models.linear import LinearBushing
from bushenv.models.narx import NarxBushing
from bushenv.scales import (
    MACHINE,
    BushingScales,
    ScaleError,
    scales_of_reference,
    stiffness_mismatch,
)
from bushenv.search.corpus import CorpusError, check, load_case, make_case, save_case
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.families import FAMILIES
from bushenv.search.targets import TARGETS


def wrong_sign_hybrid(k_n_per_m: float = 380e3) -> HybridBushing:
    """A hybrid whose network cancels twice its backbone in a hold: F = k x - 2 k x = -k x at
    rest, while it follows the backbone's damping in motion (one tanh unit on x, kept linear by
    a small input gain)."""
    net = NarxBushing.initialised((-12.5e-3, 12.5e-3), (-1.0, 1.0), seed=0)
    w1 = np.zeros_like(net.w1)
    w1[0, 0] = 1e-3  # tanh(1e-3 xs) ~ 1e-3 xs: linear in the scaled displacement
    w_out = np.zeros_like(net.w_out)
    # F_nn = f_scale * w_out * 1e-3 * x / x_scale = -2 k x
    w_out[0] = -2 * k_n_per_m * net.x_scale_m / 1e-3
    params = {k: getattr(net, k) for k in NarxBushing.param_names}
    params.update(w1=w1, b1=np.zeros_like(net.b1), w_out=w_out, b_out=0.0)
    return HybridBushing(k_n_per_m=k_n_per_m, c_ns_per_m=4.4e3, **params)


def test_a_model_that_holds_the_wrong_sign_diverges_by_the_static_criterion(reference_axial):
    model = wrong_sign_hybrid()
    x = ex.step_hold(4e-3, 4.0, DT, pre_s=0.5, rise_s=0.05)
    assert model.simulate(x)[-1] < -1000  # the model holds about -1.5 kN at +4 mm
    with BatchEvaluator(model, reference_axial, "rig") as ev:
        row = ev.evaluate([x]).verdict.row(0)
    assert row["diverged"] and "static" in row["criteria"]


def test_a_model_that_holds_a_fifth_of_the_force_diverges_by_the_static_criterion(
    reference_axial,
):
    soft = LinearBushing(k_n_per_m=45e3, c_ns_per_m=4.4e3)  # a fifth of the rubber's static
    x = ex.step_hold(4e-3, 4.0, DT, pre_s=0.5, rise_s=0.05)
    with BatchEvaluator(soft, reference_axial, "rig") as ev:
        row = ev.evaluate([x]).verdict.row(0)
    assert "static" in row["criteria"]


@pytest.mark.parametrize("axis", ["axial", "radial"])
def test_the_linear_control_never_trips_the_static_criterion(axis):
    from bushenv.models import get_model, get_reference

    rng = np.random.default_rng(5)
    profiles = []
    for name in TARGETS["rig"].family_names():
        fam = FAMILIES[name]
        for u in [np.zeros(fam.dim), np.ones(fam.dim)] + [rng.random(fam.dim) for _ in range(30)]:
            profiles.append(fam.profile(u))
    ref = get_reference("rubber", axis=axis)
    with BatchEvaluator(get_model("linear", axis=axis), ref, "rig") as ev:
        v = ev.evaluate(profiles).verdict
    assert not v.flags["static"].any()
    assert not v.diverged.any(), [v.row(b) for b in np.flatnonzero(v.diverged)][:3]


def test_without_a_reference_only_the_criteria_that_need_none_run():
    x = ex.sine(5.0, 2e-3, 2.0, DT)
    x = np.concatenate([x, np.full(400, x[-1])])
    passive = LinearBushing(k_n_per_m=380e3, c_ns_per_m=4.4e3).simulate(x)
    active = LinearBushing(k_n_per_m=380e3, c_ns_per_m=-4.4e3).simulate(x)  # negative damping
    v = judge(np.c_[x, x], np.c_[passive, active], None, DT)
    assert "deviation" not in v.criteria_run and "static" not in v.criteria_run
    assert not v.diverged[0]
    assert v.diverged[1] and v.first_criterion[1] == "energy"


def test_two_models_of_different_bushings_are_named_by_their_static_stiffness(reference_axial):
    stiff = LinearBushing(k_n_per_m=1e6, c_ns_per_m=4.4e3)
    assert "differ by a factor" in stiffness_mismatch(stiff, reference_axial)
    assert stiffness_mismatch(LinearBushing.preset("axial"), reference_axial) is None


def test_a_users_reference_sets_the_force_floor_from_its_static_stiffness():
    user = LinearBushing(k_n_per_m=1e6, c_ns_per_m=1e3)
    s = scales_of_reference(user, builtin=False)
    assert s.force_floor_n == pytest.approx(1e6 * 0.5e-3, rel=1e-6)
    assert scales_of_reference(None, builtin=True) is MACHINE
    with pytest.raises(ScaleError, match="beyond the test machine"):
        BushingScales(stroke_m=0.1)


def test_search_profiles_stay_within_the_bushings_stroke_and_velocity():
    small = BushingScales(stroke_m=2e-3, velocity_m_per_s=0.2)
    rng = np.random.default_rng(0)
    for name in TARGETS["rig"].family_names():
        fam = FAMILIES[name]
        for _ in range(10):
            x = fam.profile(rng.random(fam.dim), DT, limits=small)
            assert np.max(np.abs(x)) <= 2e-3 * (1 + 1e-9)
            assert np.max(np.abs(np.diff(x))) / DT <= 0.2 * (1 + 1e-9)


def test_a_case_replays_against_its_own_reference_and_refuses_when_it_is_gone(tmp_path):
    user_ref = LinearBushing(k_n_per_m=1e6, c_ns_per_m=2e3)
    ref_path = user_ref.save(tmp_path / "my_reference.npz")
    model = wrong_sign_hybrid(k_n_per_m=1e6)
    model_path = model.save(tmp_path / "my_hybrid.npz")
    x = ex.step_hold(2e-3, 3.0, DT, pre_s=0.5, rise_s=0.05)
    case = make_case(
        x,
        env="rig",
        axis="axial",
        family="step",
        params=None,
        found_by={"model": str(model_path)},
        models={str(model_path): model},
        reference=user_ref,
        reference_spec=str(ref_path),
    )
    assert case.expect[str(model_path)]["diverged"]
    path = save_case(case, tmp_path / "corpus")
    stored = json.loads(path.read_text())
    assert stored["reference"]["spec"] == str(ref_path) and stored["reference"]["file_sha256"]
    assert check(load_case(path)) == []
    ref_path.unlink()
    assert check(load_case(path)) == []  # the copy kept with the corpus stands in
    (path.parent / stored["reference"]["file"]["kept"]).unlink()
    with pytest.raises(CorpusError, match="its reference .* neither at .* nor kept"):
        check(load_case(path))


def test_a_reference_that_is_not_finite_makes_the_profile_unusable_not_the_model_divergent():
    class Blows(LinearBushing):
        def _advance(self, x, v, out):
            super()._advance(x, v, out)
            out[np.abs(x) > 3e-3] = np.nan  # the reference fails beyond 3 mm

    ref = Blows(k_n_per_m=380e3, c_ns_per_m=4.4e3)
    model = LinearBushing(k_n_per_m=380e3, c_ns_per_m=4.4e3)
    small = ex.step_hold(1e-3, 2.0, DT, pre_s=0.5, rise_s=0.05)
    big = ex.step_hold(5e-3, 2.0, DT, pre_s=0.5, rise_s=0.05)
    with BatchEvaluator(model, ref, "rig") as ev:
        v = ev.evaluate([small, big]).verdict
    assert not v.row(0)["reference_unusable"] and not v.diverged[0]
    assert v.row(1)["reference_unusable"] and not v.diverged[1]


def test_attack_with_a_users_reference_file_records_it_and_fits_the_control(tmp_path, capsys):
    ref = LinearBushing(k_n_per_m=1e6, c_ns_per_m=2e3).save(tmp_path / "ref.npz")
    model = LinearBushing(k_n_per_m=1.05e6, c_ns_per_m=2e3).save(tmp_path / "mine.npz")
    out = tmp_path / "run"
    argv = ["attack", "--model", str(model), "--reference", str(ref), "--budget", "16"]
    argv += ["--searchers", "random", "--out", str(out), "--no-plots", "--max-shrink", "1"]
    assert main(argv) == 0
    report = json.loads((out / "report.json").read_text())
    assert report["reference"]["spec"] == str(ref)
    assert report["criteria"]["run"][-1] == "static"
    control = [k for k, e in report["models"].items() if e["role"] == "control"]
    assert control and report["models"][control[0]]["file"].endswith("control-linear.npz")
    assert report["scales"]["force_floor_n"] == pytest.approx(500.0, rel=1e-3)
    assert not any(
        s["diverged"] for e in report["models"].values() for s in e["searchers"].values()
    )


def test_a_reference_with_a_model_card_sets_the_search_to_its_records_range(tmp_path):
    from bushenv.machine import random_test
    from bushenv.records import save_csv
    from bushenv.reference.rubber import RubberBushing

    rec = random_test(RubberBushing.preset("axial", seed=3), 1.0, duration_s=8.0, seed=3)
    train = save_csv(rec, tmp_path / "train.csv")
    ref = tmp_path / "ref.npz"
    assert main(["fit", str(train), "--model", "linear", "--out", str(ref), "--quiet"]) == 0
    model = LinearBushing(k_n_per_m=4e5, c_ns_per_m=4e3).save(tmp_path / "mine.npz")
    out = tmp_path / "run"
    argv = ["attack", "--model", str(model), "--reference", str(ref), "--budget", "8"]
    argv += ["--searchers", "random", "--out", str(out), "--no-plots", "--max-shrink", "0"]
    assert main(argv) == 0
    report = json.loads((out / "report.json").read_text())
    scales = report["scales"]
    peak = float(np.max(np.abs(rec.displacement)))
    assert scales["stroke_m"] == pytest.approx(1.5 * peak, rel=1e-9)
    assert "card's training records" in scales["source"]
    # a 0.5-20 Hz random drive shows no static behaviour: its fit cannot judge held forces,
    # nor set the floor by its static stiffness (4 % of the records' peak force instead)
    assert scales["force_floor_n"] == pytest.approx(0.04 * np.max(np.abs(rec.force)), rel=1e-9)
    assert "static" not in report["criteria"]["run"]
    assert any("static not judged" in n for n in report["notes"])


def test_without_a_reference_the_attacked_models_card_sets_the_scales(tmp_path):
    from bushenv.machine import random_test
    from bushenv.records import save_csv
    from bushenv.reference.rubber import RubberBushing

    rec = random_test(RubberBushing.preset("axial", seed=4), 1.0, duration_s=8.0, seed=4)
    train = save_csv(rec, tmp_path / "train.csv")
    mine = tmp_path / "mine.npz"
    assert main(["fit", str(train), "--model", "linear", "--out", str(mine), "--quiet"]) == 0
    out = tmp_path / "run"
    argv = ["attack", "--model", str(mine), "--budget", "8", "--searchers", "random"]
    assert main([*argv, "--out", str(out), "--no-plots", "--max-shrink", "0"]) == 0
    report = json.loads((out / "report.json").read_text())
    assert report["reference"]["spec"] is None
    peak = float(np.max(np.abs(rec.displacement)))
    assert report["scales"]["stroke_m"] == pytest.approx(1.5 * peak, rel=1e-9)
    assert report["scales"]["force_scale_n"] == pytest.approx(np.max(np.abs(rec.force)))
