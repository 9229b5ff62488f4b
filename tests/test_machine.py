import warnings

import numpy as np
import pytest

from bushenv import excitation as ex
from bushenv import machine, programmes
from bushenv.cli import main as cli_main
from bushenv.models.base import PAPER_DT
from bushenv.models.linear import LinearBushing
from bushenv.record_columns import THREE_AXES
from bushenv.record_files import load_record
from bushenv.records import load_csv


@pytest.fixture
def linear():
    return LinearBushing.preset("axial")


def test_harmonic_programme_is_seed001_grid_of_25_ten_second_sines():
    items = programmes.harmonic_programme()
    assert len(items) == 25
    assert items[0].name == "sine_1hz_0.5mm" and items[-1].name == "sine_20hz_4mm"
    assert {len(i.x) for i in items} == {2048}
    peaks = sorted({round(float(np.max(np.abs(i.x))) * 1e3, 2) for i in items})
    assert peaks == [0.5, 1.0, 2.0, 3.0, 4.0]
    for item in items:
        assert ex.within_limits(item.x, PAPER_DT)[0]


def test_run_gives_record_with_model_force_and_time_axis(linear):
    x = ex.sine(10.0, 2e-3, 1.0, PAPER_DT)
    record = machine.run(linear, x, name="s")
    expected = linear.k_n_per_m * x + linear.c_ns_per_m * np.gradient(x, PAPER_DT)
    assert np.allclose(record.force, expected, rtol=1e-12, atol=1e-9)
    assert record.dt == pytest.approx(PAPER_DT)
    assert record.time[0] == 0.0 and len(record) == 205  # round(1 s * 204.8 Hz)
    assert record.info["force_limit_exceeded"] is False


def test_run_programme_batches_equal_length_items_and_matches_single_runs(linear):
    items = programmes.harmonic_programme(frequencies_hz=(1.0, 15.0), amplitudes_m=(1e-3, 3e-3))
    items.append(programmes.step_item(dt=PAPER_DT, hold_s=1.0))
    messages = []
    records = machine.run_programme(linear, items, progress=messages.append)
    assert [r.name for r in records] == [i.name for i in items]
    assert len(messages) == 2  # one batch of four sines, one step
    for item, record in zip(items, records, strict=True):
        alone = machine.run(linear, item.x, name=item.name)
        assert np.array_equal(record.force, alone.force)


def test_run_refuses_excitation_beyond_stroke_or_velocity(linear):
    with pytest.raises(machine.MachineError, match=r"big: .*stroke limit 12\.5 mm"):
        machine.run(linear, ex.sine(1.0, 15e-3, 2.0, PAPER_DT), name="big")
    with pytest.raises(machine.MachineError, match=r"jump: .*velocity limit.*clip_to_limits"):
        machine.run(linear, ex.step_hold(10e-3, 1.0, PAPER_DT), name="jump")
    drivable = ex.clip_to_limits(ex.step_hold(10e-3, 1.0, PAPER_DT), PAPER_DT)
    assert len(machine.run(linear, drivable)) == len(drivable)


def test_run_programme_refuses_before_running_anything(linear):
    good = programmes.step_item(hold_s=1.0)
    bad = programmes.ProgrammeItem("fast", ex.sine(30.0, 10e-3, 1.0, PAPER_DT), PAPER_DT)
    with pytest.raises(machine.MachineError, match="fast"):
        machine.run_programme(linear, [good, bad])
    other_rate = programmes.step_item(hold_s=1.0, dt=1 / 1024)
    with pytest.raises(machine.MachineError, match="dt="):
        machine.run_programme(linear, [other_rate])


def test_force_beyond_25kN_is_flagged_not_refused():
    stiff = LinearBushing(k_n_per_m=1.0e7, c_ns_per_m=0.0)
    with pytest.warns(machine.MachineWarning, match=r"40 kN|4e\+04 N.*25 kN"):
        record = machine.step_test(stiff, hold_s=1.0)
    assert record.info["force_limit_exceeded"] is True
    assert record.info["max_abs_force_n"] == pytest.approx(4.0e4)


def test_random_test_identification_and_verification_sizes(linear):
    ident = machine.random_test(linear, n_index=1.0, seed=0)
    verif = machine.random_test(linear, n_index=1.5, seed=1)
    assert len(ident) == 8192 and len(verif) == 4096  # 40 s and 20 s at 204.8 Hz
    assert np.max(np.abs(ident.displacement)) == pytest.approx(2e-3)
    assert np.max(np.abs(verif.displacement)) == pytest.approx(3e-3)
    again = machine.random_test(linear, n_index=1.0, seed=0)
    assert np.array_equal(ident.force, again.force)


def test_step_test_is_4mm_held_10s_and_linear_force_settles_at_k_times_step(linear):
    record = machine.step_test(linear)
    assert record.duration_s == pytest.approx(10.5, abs=PAPER_DT)
    assert record.displacement[-1] == 4e-3
    assert record.force[-1] == pytest.approx(linear.k_n_per_m * 4e-3)


def test_papers_programme_holds_harmonic_identification_verification_and_step():
    names = [i.name for i in programmes.papers_programme(seed=5)]
    assert len(names) == 28
    assert names[-3:] == ["random_n1_40s_seed5", "random_n1.5_20s_seed6", "step_4mm_hold10s"]


def test_measure_cli_writes_records_and_refuses_to_overwrite(tmp_path, capsys):
    out = tmp_path / "rec"
    argv = ["measure", "--model", "linear", "--programme", "random", "--n", "1.5"]
    argv += ["--duration", "5", "--seed", "2", "--out", str(out)]
    assert cli_main(argv) == 0
    path = out / "random_n1.5_5s_seed2.csv"
    captured = capsys.readouterr()
    assert str(path) in captured.out and "[1/1]" in captured.err
    record = load_csv(path)
    x = ex.random_rpc(1.5, 5.0, PAPER_DT, seed=2)
    assert np.array_equal(record.displacement, x)
    assert np.array_equal(record.force, LinearBushing.preset("axial").simulate(x))
    before = path.read_bytes()
    assert cli_main(argv) == 2
    assert "already exist" in capsys.readouterr().err
    assert path.read_bytes() == before
    assert cli_main([*argv, "--force", "--quiet"]) == 0


def test_measure_cli_step_programme_uses_axis_and_rate(tmp_path):
    argv = ["measure", "--model", "linear", "--axis", "radial", "--programme", "step"]
    argv += ["--step-mm", "2", "--hold", "1", "--rate", "1024", "--out", str(tmp_path), "--quiet"]
    assert cli_main(argv) == 0
    record = load_csv(tmp_path / "step_2mm_hold1s.csv")
    assert record.sample_rate_hz == pytest.approx(1024.0)
    assert record.force[-1] == pytest.approx(1518.73e3 * 2e-3)
    # 2 mm in one sample at 1024 Hz would be 2 m/s: the step rises as fast as the machine can
    assert 1 < np.count_nonzero(np.diff(record.displacement)) < 10


def test_step_item_is_ideal_when_drivable_and_rate_limited_otherwise():
    ideal = programmes.step_item(4e-3, 1.0, PAPER_DT)
    assert np.count_nonzero(np.diff(ideal.x)) == 1
    for size in (4e-3, 10e-3, -12e-3):
        fast = programmes.step_item(size, 1.0, 1 / 2048)
        assert ex.within_limits(fast.x, 1 / 2048) == (True, "")
        assert fast.x[-1] == size


def test_reference_rubber_runs_the_papers_programme():
    pytest.importorskip("bushenv.reference.rubber")
    from bushenv.models import get_model

    rubber = get_model("rubber", axis="axial")
    with warnings.catch_warnings():
        warnings.simplefilter("error", machine.MachineWarning)
        records = machine.run_programme(rubber, programmes.papers_programme(seed=0))
    assert len(records) == 28
    for record in records:
        assert record.info["force_finite"]
        record.validate()


def test_measure_writes_a_manifest_of_what_made_the_records(tmp_path):
    import json

    out = tmp_path / "rec"
    argv = ["measure", "--model", "linear", "--programme", "step", "--out", str(out), "--quiet"]
    assert cli_main(argv) == 0
    manifest = json.loads((out / "measure.json").read_text())
    assert manifest["model"]["spec"] == "linear" and manifest["model"]["params_sha256"]
    assert manifest["records"][0]["file"].endswith(".csv")
    assert manifest["sample_rate_hz"] == 204.8


# ----- three coordinates ---------------------------------------------------------------------
@pytest.fixture(scope="module")
def records3(tmp_path_factory):
    out = tmp_path_factory.mktemp("planar_records")
    args = ["measure", "--axes", "3", "--programme", "random", "--duration", "6"]
    assert cli_main([*args, "--out", str(out / "train"), "--quiet"]) == 0
    held = ["--n", "1.5", "--seed", "5", "--out", str(out / "held"), "--quiet"]
    assert cli_main([*args, *held]) == 0
    return sorted((out / "train").glob("*.csv")), sorted((out / "held").glob("*.csv"))


def test_measure_writes_independent_and_correlated_3_axis_records(records3):
    train, held = records3
    assert [p.name for p in train] == [
        "random_correlated_n1_6s_seed0.csv",
        "random_independent_n1_6s_seed0.csv",
    ]
    assert train[0].read_text().splitlines()[0] == THREE_AXES.header_text
    rec = {p.name: load_record(p, coords=3) for p in train}
    ind = rec["random_independent_n1_6s_seed0.csv"]
    cor = rec["random_correlated_n1_6s_seed0.csv"]
    assert ind.time.size == round(6 / ind.dt)
    peak = np.abs(ind.q).max(axis=0)
    assert np.allclose(peak, [2e-3, 2e-3, 0.05], rtol=1e-6)  # amplitude index n = 1 per axis
    assert abs(np.corrcoef(cor.q[:, 0], cor.q[:, 1])[0, 1]) > 0.5
    assert abs(np.corrcoef(ind.q[:, 0], ind.q[:, 1])[0, 1]) < 0.3
    assert np.abs(load_record(held[0], coords=3).q).max() > 1.4 * np.abs(ind.q).max()


def test_measure_papers_programme_has_the_coupled_sine_sets(tmp_path):
    from bushenv.programmes import programme_items

    motions = {i.name: i.x for i in programme_items("papers", 3, 1 / 204.8)}
    names = list(motions)
    assert "radial_preload_3mm_rotation_sweep" in names
    assert "rotation_preload_0.075rad_radial_sweep" in names
    assert sum(n.startswith("random_") for n in names) == 4
    # the n = 1 sets identify: 2 mm and 0.05 rad held, each under the other's sweep, then a
    # 2 mm axial hold under a radial sweep; each addition comes last, so the records before
    # keep the noise seeds they had
    assert names[6:] == [
        "radial_preload_2mm_rotation_sweep",
        "rotation_preload_0.05rad_radial_sweep",
        "axial_preload_3mm_radial_sweep",
        "axial_preload_2mm_radial_sweep",
    ]
    at_rest = {1: 0, 2: 0, 0: 2}  # held coordinate -> the one at rest
    sets = ((names[6], 1, 2e-3, 2, 0.05), (names[7], 2, 0.05, 1, 2e-3),
            (names[9], 0, 2e-3, 1, 2e-3))  # fmt: skip
    for name, held, level, swept, swept_peak in sets:
        q = motions[name]
        assert np.allclose(q[int(2 * 204.8) :, held], level) and np.all(q[:, at_rest[held]] == 0)
        assert np.abs(q[:, swept]).max() == pytest.approx(swept_peak, rel=0.02)
    assert np.allclose(motions[names[8]][int(2 * 204.8) :, 0], 3e-3)  # n = 1.5 verifies


def _fails(args, capsys) -> str:
    assert cli_main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_measure_refuses_programmes_without_a_3_axis_form(tmp_path, capsys):
    line = _fails(["measure", "--axes", "3", "--programme", "step", "--out", str(tmp_path)], capsys)
    assert "--programme step has no 3-axis form" in line
    line = _fails(["measure", "--axes", "3", "--model", "nn", "--out", str(tmp_path)], capsys)
    assert "over 3 coordinates has no preset" in line and "its .npz file" in line
