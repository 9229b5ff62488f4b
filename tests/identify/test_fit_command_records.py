"""``bushenv fit`` on a user's own 3-axis records: what it reads, notes and refuses (exit 2)."""

import json

import numpy as np
import pytest
from standin import bushing, user_columns, write

from bushenv.cli import main
from bushenv.models import load_model
from bushenv.record_columns import THREE_AXES
from bushenv.record_files import save_columns


def fails(argv, capsys):
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    return err


def fit(paths, out, *extra):
    return main(["fit", *map(str, paths), "--out", str(out), "--quiet", *extra])


def test_a_fit_on_the_users_column_order_and_units_gives_the_si_fit(tmp_path):
    t, q, f = bushing()
    si = save_columns(tmp_path / "si.csv", t, q, f)
    user = write(tmp_path / "user.csv", *user_columns(t, q, f))
    assert fit([si], tmp_path / "a.npz", "--model", "linear") == 0
    assert fit([user], tmp_path / "b.npz", "--model", "linear") == 0
    a, b = load_model(tmp_path / "a.npz"), load_model(tmp_path / "b.npz")
    np.testing.assert_allclose(b.k_matrix, a.k_matrix, rtol=1e-6)
    assert a.dt == pytest.approx(0.002) and b.dt == pytest.approx(0.002)


def test_an_axis_with_no_force_gets_null_ratios_on_the_card_not_a_crash(tmp_path):
    t, q, f = bushing()
    q[:, 2] = 0.0
    f[:, 2] = 0.0  # a radial-axial test: the rotation column written as zeros
    rec = save_columns(tmp_path / "two_axes.csv", t, q, f)
    assert fit([rec], tmp_path / "m.npz", "--model", "linear") == 0
    card = json.loads((tmp_path / "m.card.json").read_text())
    rot = card["records"][0]["metrics"]["rotation"]
    assert rot["rms_ratio"] is None and rot["max_error_ratio"] is None
    assert rot["max_error"] == pytest.approx(0.0, abs=1e-6)
    assert card["records"][0]["metrics"]["radial"]["rms_ratio"] < 0.5


def test_records_too_short_for_a_network_are_refused_naming_them_and_the_window(tmp_path, capsys):
    rec = save_columns(tmp_path / "short.csv", *bushing(seconds=1.0))
    args = ["fit", str(rec), "--model", "hybrid", "--quiet", "--out", str(tmp_path / "m.npz")]
    line = fails(args, capsys)
    assert "500 training samples" in line and "short.csv: 500" in line
    assert "20 x --window 64 = 1280" in line and "--window 25" in line


def test_a_force_offset_is_noted_on_stderr_and_on_the_card(tmp_path, capsys):
    t, q, f = bushing()
    rec = save_columns(tmp_path / "offset.csv", t, q, f + [80.0, 0.0, 0.0])
    capsys.readouterr()
    assert fit([rec], tmp_path / "m.npz", "--model", "linear") == 0
    err = capsys.readouterr().err
    assert "note: " in err and "reads force_axial 80 N at rest" in err
    card = json.loads((tmp_path / "m.card.json").read_text())
    assert len(card["notes"]) == 1 and "load-cell offset" in card["notes"][0]
    assert "load-cell offset" in (tmp_path / "m.card.md").read_text()


def test_a_misspelt_3_axis_header_gets_the_3_axis_message(tmp_path, capsys):
    t, q, f = bushing(seconds=1.0)
    rec = write(
        tmp_path / "typo.csv", THREE_AXES.header_text.replace("rotation", "rotaion"), [t, q, f]
    )
    line = fails(["fit", str(rec), "--model", "linear", "--out", str(tmp_path / "m.npz")], capsys)
    assert "typo.csv line 1:" in line and "did you mean 'rotation'?" in line


@pytest.mark.parametrize("sep", [";", "\t"])
def test_a_3_axis_file_with_another_separator_gets_the_3_axis_message(tmp_path, capsys, sep):
    rec = tmp_path / "sep.csv"
    rec.write_text(THREE_AXES.header_text.replace(",", sep) + "\n" + sep.join("0" * 7) + "\n")
    line = fails(["fit", str(rec), "--model", "linear", "--out", str(tmp_path / "m.npz")], capsys)
    assert (
        "-separated; save the file with commas" in line and f"({THREE_AXES.header_text!r})" in line
    )


def test_a_one_axis_record_beside_3_axis_ones_is_refused(tmp_path, capsys):
    t, q, f = bushing(seconds=1.0)
    three = save_columns(tmp_path / "three.csv", t, q, f)
    one = write(tmp_path / "one.csv", "time,displacement,force", [t, q[:, 0], f[:, 0]])
    args = ["fit", str(three), "--model", "linear", "--validate", str(one)]
    line = fails([*args, "--out", str(tmp_path / "m.npz")], capsys)
    assert "three.csv is a 3-axis record (axial, radial, rotation)" in line
    assert "one.csv is a one-axis record" in line
    line = fails(
        ["fit", str(one), "--model", "hybrid-bw", "--out", str(tmp_path / "m.npz")], capsys
    )
    assert "model hybrid-bw is a three-axis model" in line and "not from one axis" in line


def test_records_at_two_rates_name_the_time_unit_to_check(tmp_path, capsys):
    t, q, f = bushing(seconds=1.0)
    slow = save_columns(tmp_path / "a.csv", t, q, f)
    fast = save_columns(tmp_path / "b.csv", t / 4, q, f)
    args = ["fit", str(slow), "--model", "linear", "--validate", str(fast)]
    line = fails([*args, "--out", str(tmp_path / "m.npz")], capsys)
    assert "b.csv line 3: sampled at 2000 Hz" in line and "a.csv at 500 Hz" in line
    assert "check both time columns' units" in line


def test_measure_with_a_model_fitted_at_another_rate_says_which_rate_to_pass(tmp_path, capsys):
    rec = save_columns(tmp_path / "r.csv", *bushing())
    assert fit([rec], tmp_path / "m.npz", "--model", "linear") == 0
    args = ["measure", "--axes", "3", "--model", str(tmp_path / "m.npz"), "--programme", "random"]
    args += ["--duration", "2", "--quiet", "--out", str(tmp_path / "out")]
    line = fails(args, capsys)
    assert "m.npz: model sampled at 500 Hz, --rate is 204.8 Hz: pass --rate 500" in line
    assert main([*args, "--rate", "500"]) == 0


def test_attack_on_rig3_runs_a_model_fitted_at_500_hz_at_its_own_rate(tmp_path, capsys):
    rec = save_columns(tmp_path / "r.csv", *bushing())
    assert fit([rec], tmp_path / "m.npz", "--model", "linear") == 0
    args = ["attack", "--env", "rig3", "--model", str(tmp_path / "m.npz"), "--budget", "2"]
    args += ["--searchers", "random", "--max-shrink", "0", "--quiet", "--out", str(tmp_path / "a")]
    # a user's file is judged by the reference given: none given, the attack says so
    assert "judges against a reference and none was given" in fails(args, capsys)
    # bushenv's reference rubber is another bushing: its vetting refuses it on the fit's records
    line = fails([*args, "--reference", "rubber"], capsys)
    assert "failed its vetting (compatibility" in line and "r.csv" in line
    # the fit itself as the judge: its 3x3 K is not symmetric (a circulatory stiffness gives
    # energy back on an orbit), so its vetting fails on passivity; trusted, it judges
    own = [*args, "--reference", str(tmp_path / "m.npz"), "--force"]
    assert "failed its vetting (passivity" in fails(own, capsys)
    assert main([*own, "--trust-reference"]) == 0  # before: "sampled at 500 Hz, expected 204.8"
    report = json.loads((tmp_path / "a" / "report.json").read_text())
    assert report["arguments"]["model"].endswith("m.npz") and report["arguments"]["budget"] == 2
    assert report["judge"]["trusted_by_flag"] is True


def test_bushenv_card_reads_a_planar_card_checks_its_records_and_shows_ratios_per_axis(
    tmp_path, capsys
):
    t, q, f = bushing()
    rec = save_columns(tmp_path / "train.csv", t, q, f)
    held = save_columns(tmp_path / "held.csv", t, q, 1.01 * f)
    assert fit([rec], tmp_path / "m.npz", "--model", "linear", "--validate", str(held)) == 0
    capsys.readouterr()
    assert main(["card", str(tmp_path / "m.npz"), str(rec)]) == 0
    out = capsys.readouterr().out
    assert "model linear in m.npz (sha256 matches)" in out
    assert "train.csv" in out and "(checked)" in out and "axial" in out and "rotation" in out
    assert "1 record file(s) match the card" in out
    assert "extrapolation:" not in out  # the held-out record moves as the training one
    wide = save_columns(tmp_path / "wide.csv", t, 1.5 * q, f)
    assert fit([rec], tmp_path / "w.npz", "--model", "linear", "--validate", str(wide)) == 0
    capsys.readouterr()
    assert main(["card", str(tmp_path / "w.npz")]) == 0
    assert "extrapolation: wide.csv goes beyond" in capsys.readouterr().out
    held.write_text(held.read_text().replace("0", "1", 5))  # the held-out record changed
    line = fails(["card", str(tmp_path / "m.npz"), str(held)], capsys)
    assert "held.csv does not match the card" in line


def test_bushrig3_with_a_fit_at_another_rate_names_the_dt_s_to_pass(tmp_path):
    import gymnasium as gym

    from bushenv.rigs.common import RigError

    rec = save_columns(tmp_path / "r.csv", *bushing())  # 500 Hz records
    assert fit([rec], tmp_path / "m.npz", "--model", "linear") == 0
    with pytest.raises(RigError, match=r"model sampled at 500 Hz, expected 204.8 Hz.*dt_s=0\.002"):
        gym.make("BushRig3-v0", model=str(tmp_path / "m.npz"))
    env = gym.make("BushRig3-v0", model=str(tmp_path / "m.npz"), dt_s=0.002, reference="linear")
    env.reset(seed=0)
    env.close()


def test_a_fit_draws_forces_and_loops_per_coordinate_of_each_held_out_record(tmp_path):
    t, q, f = bushing()
    train = save_columns(tmp_path / "train.csv", t, q, f)
    held = save_columns(tmp_path / "held.csv", t, q * 0.8, f * 0.8)
    assert fit([train], tmp_path / "m.npz", "--model", "linear", "--validate", str(held)) == 0
    card = json.loads((tmp_path / "m.card.json").read_text())
    assert card["plots"] == ["m.1-held.time.png", "m.1-held.loops.png"]
    for name in card["plots"]:
        assert (tmp_path / name).read_bytes()[:4] == b"\x89PNG"
        assert f"![{name}]({name})" in (tmp_path / "m.card.md").read_text()
    assert fit([train], tmp_path / "n.npz", "--model", "linear", "--no-plots") == 0
    assert "plots" not in json.loads((tmp_path / "n.card.json").read_text())
    assert not list(tmp_path.glob("n.*.png"))


def test_a_bouc_wen_fit_has_no_clock_by_default_and_repeats_to_the_bit(tmp_path):
    from bushenv.identify.mimo import HybridBWOptions
    from bushenv.identify.vector_boucwen import VectorBoucWenOptions

    assert VectorBoucWenOptions().time_limit_s == 0 and HybridBWOptions().time_limit_s == 0
    rec = save_columns(tmp_path / "r.csv", *bushing())
    for name in ("a", "b"):
        assert fit([rec], tmp_path / f"{name}.npz", "--model", "boucwen", "--evaluations", "6") == 0
    a, b = load_model(tmp_path / "a.npz"), load_model(tmp_path / "b.npz")
    for key in a.param_names:
        np.testing.assert_array_equal(getattr(a, key), getattr(b, key), err_msg=key)
    source = json.loads((tmp_path / "a.card.json").read_text())["source"]
    assert source["info"]["time_limited"] is False
