import json

import numpy as np

from bushenv.cli import main
from bushenv.diagnose.validation.reference_cases import case_label, classes, make_case
from bushenv.diagnose.validation.validate import summarise
from bushenv.diagnose.validation.widened_cases import make_widened_case


def test_case_mix_cycles_through_all_classes_and_puts_a_pair_in_every_fourth_case():
    rng = np.random.default_rng(0)
    labels = [case_label(i, rng) for i in range(28)]
    singles = [lab[0] if lab else "none" for i, lab in enumerate(labels) if i % 4 != 3]
    assert sorted(set(singles)) == sorted(classes())
    assert all(len(labels[i]) == 2 and labels[i][0] != labels[i][1] for i in range(3, 28, 4))


def test_cases_are_deterministic_and_the_records_carry_no_label():
    a = make_case(5, 2)
    b = make_case(5, 2)
    assert a.label == b.label
    assert np.array_equal(a.train[0].force, b.train[0].force)
    assert np.array_equal(a.tests[1].displacement, b.tests[1].displacement)
    names = [a.train[0].name] + [t.name for t in a.tests]
    assert names == ["train", "test1", "test2"]
    assert not a.train[0].info


def test_fast_blind_slice_names_single_effects_and_prints_a_confusion_matrix(tmp_path, capsys):
    out = tmp_path / "val"
    assert (
        main(["diagnose-validate", "--cases", "7", "--seed", "0", "--out", str(out), "--quiet"])
        == 0
    )
    printed = capsys.readouterr().out
    assert "| true \\ named | none | relaxation" in printed
    data = json.loads((out / "validation.json").read_text())
    summary = data["summary"]
    assert summary["cases"] == 7 and summary["single_cases"] == 6
    assert sum(map(sum, summary["confusion"])) == 6
    assert summary["single_top1_rate"] >= 5 / 6
    assert (out / "validation.md").read_text().startswith("`bushenv diagnose-validate")


def test_summary_counts_a_pair_hit_only_when_both_effects_are_in_the_top_two():
    rows = [
        {"kind": "pair", "label": "friction+delay", "right": True, "pair_named": True},
        {"kind": "pair", "label": "friction+delay", "right": False, "pair_named": False},
        {"kind": "single", "label": "none", "top1": "none", "right": True, "exact": True},
    ]
    rows[0]["shrink"], rows[1]["shrink"], rows[2]["shrink"] = 0.8, 0.5, 0.0
    s = summarise(rows)
    assert s["pair_hit_rate"] == 0.5
    assert s["single_top1_rate"] == 1.0
    assert s["median_shrink_named_right"] == 0.8  # 'none' cases do not count toward shrink


def test_widened_cases_are_deterministic_and_show_their_effects():
    a, b = make_widened_case(1, 1), make_widened_case(1, 1)
    assert a.label == b.label and a.label
    assert np.array_equal(a.tests[0].force, b.tests[0].force)
    for name, seen in a.drawn["visible"].items():
        assert seen > 0.02, (name, seen)  # the label describes something the records show


def test_widened_quasi_static_cases_are_50_hz_pulls_and_holds_of_metres_scale_judged_cross():
    case = make_widened_case(0, 4)
    assert case.cross
    assert all(abs(r.dt - 0.02) < 1e-12 for r in case.train + case.tests)
    peak = max(float(np.max(r.displacement)) for r in case.train + case.tests)
    assert 0.04 <= peak <= 0.17
    assert min(float(np.min(r.displacement)) for r in case.train) > -1e-3  # pulls only


def test_each_reference_draw_switches_on_the_reference_effect_named_by_its_label():
    # the reference's effect switches are its own list (it sits below the diagnosis): the
    # labels of the reference set name candidates, and each draw must set exactly the
    # reference effect of that name, or the scoring would judge against a wrong label
    from bushenv.diagnose.candidates import effect_names
    from bushenv.diagnose.validation.reference_cases import DRAWS, Draw
    from bushenv.reference.rubber import RubberBushing

    assert set(DRAWS) <= set(effect_names())
    x = 2e-3 * np.sin(np.linspace(0, 60, 4000))
    for name, draw in DRAWS.items():
        params = draw(Draw(np.random.default_rng(0), 4e5, 4e3, 3e-3, x, 1 / 204.8))
        model = RubberBushing(dt=1 / 204.8, k_n_per_m=4e5, c_ns_per_m=4e3, **params)
        assert model.active_effects == (name,), (name, model.active_effects)
