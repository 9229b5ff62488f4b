"""Fits depend only on records, options and seed; a time limit is explicit and reported; cards
list physical parameters and name records relative to themselves."""

import json
import shutil

import numpy as np
import pytest
from standin import DT, standin_drive, standin_force

from bushenv.cli import main
from bushenv.identify import IdentificationError, fit
from bushenv.identify.card import load_card, save_fit
from bushenv.identify.data import training_set
from bushenv.identify.narx_data import narx_problem
from bushenv.identify.neural import linear_check
from bushenv.models.kernels import BW_ORDER
from bushenv.records import Record, save_csv

QUICK_NN = dict(
    teacher_steps=60,
    window_lengths=(10, 30),
    iters_per_length=(15, 15),
    batch_windows=4,
    eval_every=5,
    choose="off",
)
QUICK_BW = dict(generations=3, population=3, fit_seconds=1.0, polish_evaluations=10)


def record(duration_s, seed, name):
    x = standin_drive(duration_s, seed=seed)
    return Record.from_arrays(x, standin_force(x), DT, name=name)


def saved_arrays(model, path):
    model.save(path)
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


@pytest.mark.parametrize(
    "model, options",
    [
        ("linear", None),
        ("nn", QUICK_NN),
        ("hybrid", QUICK_NN),
        ("nn", dict(QUICK_NN, choose="on", choose_networks=("4x2", "8x4"))),
        ("boucwen", QUICK_BW),
    ],
)
def test_two_fits_with_one_seed_give_bit_equal_model_files(model, options, tmp_path):
    rec = record(4.0, 0, "a")
    one = saved_arrays(fit([rec], model, options, seed=3, progress=False).model, tmp_path / "1.npz")
    two = saved_arrays(fit([rec], model, options, seed=3, progress=False).model, tmp_path / "2.npz")
    assert one.keys() == two.keys()
    for key in one:
        assert np.array_equal(one[key], two[key]), key  # every element, every bit


@pytest.mark.parametrize("model, options", [("nn", QUICK_NN), ("boucwen", QUICK_BW)])
def test_no_fit_stops_on_the_clock_unless_asked(model, options):
    res = fit([record(4.0, 0, "a")], model, options, progress=False)
    assert res.options.time_limit_s == 0.0
    tr = res.model.training
    assert tr["time_limited"] is False
    used = tr["budget_used"]
    if model == "boucwen":
        assert used["generations"] == used["generations_planned"] == 3
    else:
        assert used["teacher_steps"] == used["teacher_steps_planned"] == 60


@pytest.mark.parametrize(
    "model, flags, planned",
    [
        ("nn", ["--teacher-steps", "100000", "--choose", "off"], "teacher_steps"),
        ("boucwen", ["--generations", "100000", "--population", "3", "--fit-seconds", "1"], None),
    ],
)
def test_a_tiny_time_limit_stops_the_fit_says_so_and_the_card_records_it(
    model, flags, planned, tmp_path, capsys
):
    path = save_csv(record(3.0, 0, "a"), tmp_path / "a.csv")
    out = tmp_path / "m.npz"
    args = ["fit", str(path), "--model", model, "--out", str(out), "--no-plots", "--quiet"]
    assert main([*args, *flags, "--time-limit-s", "0.2"]) == 0
    stdout = capsys.readouterr().out
    assert "stopped early: time limit 0.2 s hit" in stdout
    src = json.loads(out.with_name("m.card.json").read_text())["source"]
    assert src["time_limited"] is True and "time limit 0.2 s" in src["stopped"]
    used = src["budget_used"]
    if model == "boucwen":
        assert 1 <= used["generations"] < used["generations_planned"] == 100000
    else:
        assert 1 <= used[planned] < used[planned + "_planned"] == 100000
    assert "**stopped early**" in out.with_name("m.card.md").read_text()


def test_linear_and_boucwen_cards_list_their_physical_parameters(tmp_path):
    rec = record(3.0, 0, "a")
    lin = fit([rec], "linear", progress=False)
    card = save_fit(lin, tmp_path / "lin.npz", plots=False)
    assert card["parameters"] == {
        "k_n_per_m": {"value": lin.model.k_n_per_m, "unit": "N/m"},
        "c_ns_per_m": {"value": lin.model.c_ns_per_m, "unit": "N s/m"},
    }
    assert (
        f"| k_n_per_m | {lin.model.k_n_per_m:.6g} | N/m |" in (tmp_path / "lin.card.md").read_text()
    )
    bw = fit([rec], "boucwen", QUICK_BW, progress=False)
    params = save_fit(bw, tmp_path / "bw.npz", plots=False)["parameters"]
    assert list(params) == list(BW_ORDER) and len(params) == 16
    assert [p["value"] for p in params.values()] == bw.model.vector().tolist()
    nn = fit([rec], "nn", QUICK_NN, progress=False)
    assert save_fit(nn, tmp_path / "nn.npz", plots=False)["parameters"] is None


def test_card_names_records_relative_to_itself_and_a_moved_folder_still_checks(tmp_path):
    work = tmp_path / "work"
    (work / "records").mkdir(parents=True)
    train = save_csv(record(3.0, 0, "train"), work / "records" / "train.csv")
    (work / "models").mkdir()
    assert main(["fit", str(train), "--model", "linear", "--out", str(work / "models" / "m.npz"),
                 "--no-plots", "--quiet"]) == 0  # fmt: skip
    data = json.loads((work / "models" / "m.card.json").read_text())
    assert data["records"][0]["file"] == "../records/train.csv"
    moved = tmp_path / "elsewhere"
    shutil.move(work, moved)
    card = load_card(moved / "models" / "m.npz")
    path = card.record_path(card.records[0])
    assert path.resolve() == (moved / "records" / "train.csv").resolve()
    load_card(moved / "models" / "m.npz", records=[path])  # the hash still matches


def test_a_card_with_absolute_record_paths_still_loads(tmp_path):
    train = save_csv(record(3.0, 0, "train"), tmp_path / "train.csv")
    card = save_fit(fit([train], "linear", progress=False), tmp_path / "m.npz", plots=False)
    card["records"][0]["file"] = str(train.resolve())  # as cards before relative paths
    (tmp_path / "m.card.json").write_text(json.dumps(card))
    back = load_card(tmp_path / "m.npz", records=[train])
    assert back.record_path(back.records[0]) == train.resolve()


def test_the_fit_table_shows_whole_record_names(tmp_path, capsys):
    deep = tmp_path / "a_folder_with_a_long_name" / "records_of_the_bushing"
    deep.mkdir(parents=True)
    train = save_csv(record(3.0, 0, "t"), deep / "radial_train_record_n1.csv")
    out = tmp_path / "m.npz"
    assert main(["fit", str(train), "--model", "linear", "--out", str(out), "--quiet"]) == 0
    stdout = capsys.readouterr().out
    assert str(train) in stdout
    assert "parameters: k_n_per_m = " in stdout


def test_the_nn_network_is_chosen_on_validation_and_the_card_says_which(tmp_path):
    rec = record(4.0, 0, "a")
    opts = dict(QUICK_NN, choose="on", choose_networks=("4x2", "6x3"))
    res = fit([rec], "nn", opts, seed=1, progress=False)
    choice = res.model.training["choice"]
    scores = {
        (c["hidden"][0], c["n_past_x"]): c["validation_rms_ratio"] for c in choice["candidates"]
    }
    best = min(scores, key=scores.get)
    # the network returned is the best-scoring candidate, and the options on the card say so
    assert (res.options.hidden, res.options.n_past_x, res.options.n_past_f) == (
        (best[0],),
        best[1],
        best[1],
    )
    assert res.model.n_past_x == best[1] and res.model.w1.shape[0] == best[0]
    card = save_fit(res, tmp_path / "nn.npz", plots=False)
    assert card["source"]["options"]["hidden"] == [best[0]]
    assert card["source"]["choice"]["summary"].startswith(f"{best[0]} units, lags {best[1]}")


def test_giving_a_size_or_lags_turns_the_choice_off():
    res = fit(
        [record(4.0, 0, "a")], "nn", dict(QUICK_NN, choose="on") | {"hidden": (5,)}, progress=False
    )
    assert res.model.training["choice"] is not None  # choose given explicitly wins
    given = {k: v for k, v in QUICK_NN.items() if k != "choose"} | {"n_past_x": 3}
    res = fit([record(4.0, 0, "a")], "nn", given, progress=False)
    assert res.options.choose == "off" and res.model.training["choice"] is None


def test_an_nn_that_learns_less_than_a_linear_model_gets_a_note_on_its_card(tmp_path):
    untrained = dict(QUICK_NN, teacher_steps=1, iters_per_length=(0, 0))
    res = fit([record(4.0, 0, "a")], "nn", untrained, progress=False)
    tr = res.model.training
    assert tr["linear_validation_rms_ratio"] < 0.5 < tr["best_validation_rms_ratio"]
    card = save_fit(res, tmp_path / "nn.npz", plots=False)
    assert "learned little beyond a spring and a damper" in card["source"]["note"]
    # the rule itself: a network with less than half the linear model's error gets no note
    problem = narx_problem("nn", training_set([record(4.0, 0, "a")]), 5, 5, 0.2)
    lin = linear_check(problem, 1.0)["linear_validation_rms_ratio"]
    assert linear_check(problem, 0.49 * lin)["note"] is None
    assert linear_check(problem, 0.51 * lin)["note"] is not None


def test_a_candidate_that_is_not_units_x_lags_is_refused_naming_it():
    with pytest.raises(IdentificationError, match="'9y5' is not UNITSxLAGS"):
        fit([record(3.0, 0, "a")], "nn", dict(QUICK_NN, choose="on", choose_networks="9x5,9y5"))
