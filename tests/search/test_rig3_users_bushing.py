"""``bushenv attack --env rig3`` on a user's bushing: limits from the reference's card, the
control fitted to the reference, failing profiles saved, coverage per coordinate in its unit,
resume."""

import json
from pathlib import Path

import numpy as np
import pytest

from bushenv.cli import main
from bushenv.models.planar_linear import PlanarLinear, fit_linear
from bushenv.persist import load_profiles
from bushenv.record_files import load_record
from bushenv.search.families import FAMILIES
from bushenv.search.limits import COORDS, CoordinateLimits, machine_limits
from bushenv.search.targets import TARGETS

TRAIN = "random_independent_n1_8s_seed0.csv"


@pytest.fixture(scope="module")
def bushing(tmp_path_factory) -> Path:
    """Three-axis records of the coupled reference, a linear fit with its card (the user's
    reference) and a model of negative damping (no card) that fails on it."""
    d = tmp_path_factory.mktemp("rig3-user")
    assert main(["measure", "--axes", "3", "--programme", "random", "--duration", "8",
                 "--out", str(d / "rec3"), "--quiet"]) == 0  # fmt: skip
    train, held = d / "rec3" / TRAIN, d / "rec3" / "random_correlated_n1_8s_seed0.csv"
    assert main(["fit", str(train), "--validate", str(held), "--model", "linear", "--out",
                 str(d / "ref3.npz"), "--no-plots", "--quiet"]) == 0  # fmt: skip
    ref = PlanarLinear.preset()
    PlanarLinear(0.5 * ref.k_matrix, -ref.c_matrix, ref.dt).save(d / "active3.npz")
    return d


def _attack(d: Path, out: str, *extra: str, quiet: bool = True) -> dict:
    args = ["attack", "--env", "rig3", "--model", str(d / "active3.npz"), "--reference",
            str(d / "ref3.npz"), "--budget", "12", "--max-shrink", "1", "--shrink-budget", "10",
            "--threads", "1", "--no-plots", "--out", str(d / out), *extra]  # fmt: skip
    if quiet:
        args.append("--quiet")
    assert main(args) == 0
    return json.loads((d / out / "report.json").read_text())


def _searches(report: dict, key: str = "active3") -> list[dict]:
    """The summaries of the searches against model ``key``, in the order they ran."""
    return list(report["models"][key]["searchers"].values())


@pytest.fixture(scope="module")
def attacked(bushing) -> dict:
    return _attack(bushing, "att")


def test_a_users_reference_sets_stroke_and_rate_per_coordinate_from_its_cards_records(
    bushing, attacked
):
    rec = load_record(bushing / "rec3" / TRAIN, coords=3)
    peak = np.max(np.abs(rec.q), axis=0)
    speed = np.max(np.abs(np.diff(rec.q, axis=0)), axis=0) / rec.dt
    lim = attacked["scales"]
    for i, (c, u, r) in enumerate(
        zip(COORDS, ("mm", "mm", "mrad"), ("m", "m", "rad"), strict=True)
    ):
        assert lim[c][f"stroke_{u}"] == pytest.approx(1.5e3 * peak[i], rel=1e-5)
        assert lim[c][f"rate_{r}_per_s"] == pytest.approx(1.5 * speed[i], rel=1e-5)
        assert lim[c][f"records_peak_{u}"] == pytest.approx(1e3 * peak[i], rel=1e-5)
    assert "ref3.card.json" in lim["source"]
    stroke = 1.5 * peak
    for s in _searches(attacked):
        profiles, _ = load_profiles(bushing / "att" / s["profiles_file"])
        for q in profiles:
            assert np.all(np.max(np.abs(q), axis=0) <= stroke * (1 + 1e-9))
    assert attacked["failure_reach"]["max"] <= 1.5 + 1e-9


def test_stroke_mm_sets_axial_and_radial_and_the_rotation_keeps_the_cards(bushing, attacked):
    report = _attack(bushing, "att-stroke", "--stroke-mm", "1.5", "--searchers", "random")
    lim = report["scales"]
    assert lim["axial"]["stroke_mm"] == lim["radial"]["stroke_mm"] == 1.5
    assert lim["rotation"] == attacked["scales"]["rotation"]
    assert "--stroke-mm 1.5" in lim["source"]


def test_the_control_is_a_linear_fit_to_the_users_reference_and_named_as_such(bushing, attacked):
    from bushenv.models import load_model

    control = attacked["control"]
    fitted = load_model(control["file"], coords=3)
    ref = load_model(bushing / "ref3.npz", coords=3)
    q = load_record(bushing / "rec3" / TRAIN, coords=3).q
    v = np.gradient(q, ref.dt, axis=0)
    expected = fit_linear(q, v, ref.copy().simulate(q, v), dt=ref.dt)
    assert np.allclose(fitted.k_matrix, expected.k_matrix, rtol=1e-9)
    assert np.allclose(fitted.c_matrix, expected.c_matrix, rtol=1e-9)
    assert "ref3.npz" in control["label"] and control["file"] in control["label"]
    assert attacked["models"]["linear-fit"]["role"] == "control"
    assert "linear-fit" in attacked["recheck"]
    md = (bushing / "att" / "report.md").read_text()
    assert f"control: {control['label']} ({control['how']})" in md


def test_the_one_resolve_stage_scales_to_the_users_card_and_fits_the_control(bushing, tmp_path):
    """The three-axis attack resolves through the one ``resolve`` (as a one-axis attack does):
    a ``Resolved`` whose limits come from the user's card, whose reference is vetted within
    them and whose control is a linear fit to the user's reference, under its own role."""
    from bushenv.search.campaign_config import CampaignConfig
    from bushenv.search.campaign_resolve import Resolved, resolve

    config = CampaignConfig(model=str(bushing / "active3.npz"), reference=str(bushing / "ref3.npz"),
                            target="rig3", out=tmp_path)  # fmt: skip
    r = resolve(config)
    assert isinstance(r, Resolved) and r.target.coords == COORDS
    assert r.limits.stroke != machine_limits().stroke and "ref3.card.json" in r.limits.source
    assert r.judge.scales == r.limits and r.judge.vetting.passed
    assert r.judged["stroke"] == pytest.approx(dict(zip(COORDS, r.limits.stroke, strict=True)))
    assert r.roles == {"active3": "target", "linear-fit": "control"}
    assert r.control_key == "linear-fit" and r.hybrid_key is None
    assert r.control["file"] == str(tmp_path / "models" / "control-linear.npz")
    assert r.models[r.control_key].model.dt == r.dt == r.judge.reference.dt


def test_the_warning_names_a_flagged_control_given_by_the_user(bushing, capsys):
    _attack(bushing, "att-ctl", "--control", str(bushing / "active3.npz"), "--searchers",
            "random", quiet=False)  # fmt: skip
    err = capsys.readouterr().err
    assert f"WARNING: the control ({bushing / 'active3.npz'}) was flagged" in err
    assert "(linear)" not in err


def test_every_failing_profile_is_saved_with_three_coordinates(bushing, attacked):
    for s in _searches(attacked):
        profiles, meta = load_profiles(bushing / "att" / s["profiles_file"])
        failing = [m for m in meta if m["diverged"] and not m.get("worst")]
        assert len(failing) == min(s["n_failures"], 256) > 0
        assert all(q.ndim == 2 and q.shape[1] == 3 for q in profiles)
        assert [m.get("worst") for m in meta].count(True) == 1


def test_coverage_is_per_coordinate_with_its_unit_in_the_key(attacked):
    stroke = attacked["scales"]
    for s in _searches(attacked):
        for row in s["coverage"].values():
            assert set(row) == {"profiles", *COORDS}
            assert set(row["axial"]) == {"peak_mm_min", "peak_mm_max", "max_rate_m_per_s"}
            assert set(row["rotation"]) == {"peak_mrad_min", "peak_mrad_max",
                                            "max_rate_rad_per_s"}  # fmt: skip
            assert row["rotation"]["peak_mrad_max"] <= stroke["rotation"]["stroke_mrad"] + 1e-6
            assert row["axial"]["peak_mm_max"] <= stroke["axial"]["stroke_mm"] + 1e-6


def _untimed(obj):
    """``obj`` without its wall times."""
    if isinstance(obj, dict):
        return {k: _untimed(v) for k, v in obj.items() if not k.startswith("seconds")}
    if isinstance(obj, list):
        return [_untimed(v) for v in obj]
    return obj


def test_resume_finishes_an_interrupted_attack_as_the_uninterrupted_one(bushing, attacked, capsys):
    import shutil

    out = bushing / "att-resume"
    shutil.copytree(bushing / "att", out)
    report = json.loads((out / "report.json").read_text())
    searches = report["models"]["active3"]["searchers"]
    first = next(iter(searches))
    report["models"]["active3"]["searchers"] = {first: searches[first]}  # stopped after one
    report["recheck"], report["shrunk"], report["complete"] = {}, [], False
    report.pop("failure_reach", None)
    (out / "report.json").write_text(json.dumps(report))
    resumed = _attack(bushing, "att-resume", "--resume")
    for key in ("models", "recheck", "shrunk", "scales", "control", "failure_reach"):
        a, b = json.dumps(_untimed(resumed[key])), json.dumps(_untimed(attacked[key]))
        assert a.replace("att-resume", "att") == b, key
    capsys.readouterr()
    with pytest.raises(AssertionError):
        _attack(bushing, "att-resume", "--resume", "--budget", "13")
    assert "was made with budget=12, not 13" in capsys.readouterr().err


def test_the_builtin_reference_keeps_the_machine_and_the_linear_preset(tmp_path):
    ref = PlanarLinear.preset()
    PlanarLinear(ref.k_matrix, -0.3 * ref.c_matrix, ref.dt).save(tmp_path / "a.npz")
    assert main(["attack", "--env", "rig3", "--model", str(tmp_path / "a.npz"), "--budget", "4",
                 "--reference", "rubber",
                 "--searchers", "random", "--max-shrink", "0", "--threads", "1", "--no-plots",
                 "--quiet", "--out", str(tmp_path / "o")]) == 0  # fmt: skip
    report = json.loads((tmp_path / "o" / "report.json").read_text())
    assert report["scales"] == machine_limits().to_json()
    assert report["control"]["label"] == "linear"
    assert "failure_reach" not in report


@pytest.mark.parametrize("name", TARGETS["rig3"].family_names())
def test_every_family_stays_within_small_limits_of_a_users_bushing(name):
    lim = CoordinateLimits((2e-3, 1e-3, 0.02), (0.05, 0.2, 0.5))
    fam = FAMILIES[name]
    rng = np.random.default_rng(4)
    dt = PlanarLinear.preset().dt
    for _ in range(10):
        q = fam.profile(rng.random(fam.dim), dt, limits=lim)
        assert np.all(np.max(np.abs(q), axis=0) <= np.array(lim.stroke) * (1 + 1e-12))
        rate = np.max(np.abs(np.diff(q, axis=0)), axis=0) / dt
        assert np.all(rate <= np.array(lim.rate) * (1 + 1e-9))


def test_the_covered_search_is_the_searchers_own_run():
    from bushenv.search.evaluate import BatchEvaluator
    from bushenv.search.searchers import SEARCHERS
    from bushenv.search.target_base import covered_search

    ref = PlanarLinear.preset()
    model = PlanarLinear(ref.k_matrix, -0.3 * ref.c_matrix, ref.dt)
    for name in ("random", "cma"):
        with BatchEvaluator(model, ref, "rig3") as ev:
            plain = SEARCHERS[name].make().run(ev, 8, seed=3).summary()
        with BatchEvaluator(model, ref, "rig3") as ev:
            covered, per_coordinate = covered_search(SEARCHERS[name].make(), ev, 8, 3)
        covered = covered.summary()
        for s in (plain, covered):
            s.pop("seconds"), s.pop("seconds_to_failure")
        assert covered == plain
        assert set(per_coordinate) == set(plain["coverage"])


def test_a_model_that_is_no_network_skips_the_hold_stage_and_says_why(attacked):
    assert attacked["hold_stage"] == {"run": False, "why": "not a NARX network (no certificate)"}
    assert "cert-holds" not in attacked["models"]["active3"]["searchers"]


@pytest.fixture(scope="module")
def network(bushing) -> Path:
    path = bushing / "nn3.npz"
    short = ["--teacher-steps", "40", "--free-run-steps", "20"]
    assert main(["fit", str(bushing / "rec3" / TRAIN), "--model", "nn", "--out", str(path),
                 "--no-plots", "--quiet", *short]) == 0  # fmt: skip
    return path


def test_the_hold_stage_steps_to_each_suspect_hold_within_the_limits_and_judges_it(network):
    from bushenv.models import load_model
    from bushenv.search.campaign_holds import VECTOR_KINDS, CertificateHolds, listed_vectors
    from bushenv.search.evaluate import BatchEvaluator
    from bushenv.search.target_base import covered_search

    model = load_model(network, coords=3)
    lim = CoordinateLimits((3e-3, 3e-3, 0.075), (0.2, 0.2, 5.0))
    holds = listed_vectors(model, lim.stroke, floors=np.zeros(3))  # no floor: every push counts
    assert holds, "a network with no floor to its pushes lists some hold"
    for h in holds:
        assert set(h["kinds"]) <= set(VECTOR_KINDS) and h["kinds"]
        assert np.all(np.abs(h["q"]) <= np.array(lim.stroke) * (1 + 1e-12))
    assert listed_vectors(PlanarLinear.preset(), lim.stroke, np.zeros(3)) is None
    stage = CertificateHolds(holds, lim.rate, "step_hold3")
    with BatchEvaluator(model, PlanarLinear.preset(), "rig3", scales=lim) as ev:
        result, covered = covered_search(stage, ev, len(holds), 0)
    assert result.evaluations == len(holds) and set(covered) == {"step_hold3"}
    assert covered["step_hold3"]["rotation"]["max_rate_rad_per_s"] <= 5.0 + 1e-9
    entry = stage.entry()
    assert entry["listed"] == len(entry["holds"]) == len(holds)
    assert entry["confirmed"] == sum(h["confirmed"] for h in entry["holds"])


def test_an_attack_on_a_network_runs_the_hold_stage(bushing, network):
    report = _attack(bushing, "att-nn", "--model", str(network), "--searchers", "random")
    stage = report["hold_stage"]
    assert stage["run"] and stage["grid_points"] == 5
    names = list(report["models"]["nn3"]["searchers"])
    assert names == (["random", "cert-holds"] if stage["listed"] else ["random"])


def test_a_stroke_beyond_the_machine_is_refused_in_mm(bushing, capsys):
    with pytest.raises(AssertionError):
        _attack(bushing, "att-far", "--stroke-mm", "20", "--searchers", "random")
    err = capsys.readouterr().err
    assert "the axial stroke must be in (0, 12.5] mm (BushRig3-v0's), got 20 mm" in err


def test_rotation_mrad_sets_the_rotations_range_and_is_refused_without_one(tmp_path, capsys):
    from bushenv.cli import main

    argv = ["attack", "--env", "rig3", "--model", "linear", "--budget", "4", "--max-shrink", "0",
            "--searchers", "random", "--rotation-mrad", "40", "--no-plots", "--quiet",
            "--out", str(tmp_path / "a")]  # fmt: skip
    assert main(argv) in (0, 1)
    report = json.loads((tmp_path / "a" / "report.json").read_text())
    assert report["scales"]["rotation"]["stroke_mrad"] == 40.0
    assert "--rotation-mrad 40 on the rotation" in report["scales"]["source"]
    assert report["scales"]["axial"]["stroke_mm"] == 12.5
    capsys.readouterr()
    assert main(["attack", "--rotation-mrad", "40", "--out", str(tmp_path / "b")]) == 2
    assert "--env rig has no rotation" in capsys.readouterr().err
