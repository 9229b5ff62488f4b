"""bushenv.identify.fit: several records, each its own history; options; recipes; loss terms."""

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest
import torch
from standin import DT, standin_drive, standin_force

from bushenv.identify import IdentificationError, fit, fit_model
from bushenv.identify.data import training_set
from bushenv.identify.narx_data import narx_problem
from bushenv.identify.options import as_dict
from bushenv.metrics import rms_ratio
from bushenv.records import Record

QUICK = dict(
    teacher_steps=150,
    window_lengths=(10, 30),
    iters_per_length=(20, 20),
    batch_windows=8,
    eval_every=10,
)


def record(duration_s, seed, dt=DT, name=None, peak_m=0.002):
    x = standin_drive(duration_s, seed=seed, peak_m=peak_m)
    return Record.from_arrays(x, standin_force(x, dt), dt, name=name or f"rec{seed}")


def test_linear_fit_over_two_records_differentiates_each_record_alone():
    # Two records joined end to end have a jump at the seam; each record's own velocity
    # (central difference inside it) must be used, never one across the seam.
    a, b = record(2.0, 0), record(2.0, 1, peak_m=0.001)
    b.displacement += 5e-4  # the seam jumps by 0.5 mm
    b.force += 300e3 * 5e-4
    two = fit([a, b], "linear", progress=False).model
    x = np.concatenate([a.displacement, b.displacement])
    f = np.concatenate([a.force, b.force])
    v = np.concatenate([np.gradient(a.displacement, DT), np.gradient(b.displacement, DT)])
    (k, c), *_ = np.linalg.lstsq(np.column_stack([x, v]), f, rcond=None)
    assert two.k_n_per_m == pytest.approx(k, rel=1e-12)
    assert two.c_ns_per_m == pytest.approx(c, rel=1e-12)
    joined = fit_model("linear", x, f, DT, progress=False)
    assert abs(joined.c_ns_per_m - c) > 1e-3 * abs(c)  # the seam would have biased it


def test_narx_history_never_reaches_into_another_record():
    a, b = record(3.0, 0), record(2.0, 1)
    data = training_set([a, b])
    p = narx_problem("nn", data, 5, 3, 0.2)
    (lo_a, hi_a), (lo_b, hi_b) = p.train
    # the lagged inputs of record b's first prediction are b's rest padding, not a's samples
    inp, _ = p.one_step_batch([(lo_b, lo_b + 1)])
    x_rest = (0.0 - p.x_off) / p.x_sc
    y_rest = (0.0 - p.f_off) / p.f_sc
    assert np.allclose(inp[0, 1:6].numpy(), x_rest) and np.allclose(inp[0, 6:].numpy(), y_rest)
    # every free-run window of 30 samples (with its 5 lags) lies inside one record
    starts = p.window_starts(30)
    inside = ((starts >= lo_a) & (starts + 30 <= hi_a)) | ((starts >= lo_b) & (starts + 30 <= hi_b))
    assert inside.all() and starts.size == (hi_a - lo_a - 29) + (hi_b - lo_b - 29)
    assert lo_b - p.pad >= hi_a + (len(a.force) - (hi_a - lo_a))  # b's pad follows a's end


def test_two_records_train_together_and_one_record_gives_the_same_as_fit_model():
    a, b = record(4.0, 0), record(4.0, 1)
    one = fit([a], "nn", QUICK, seed=3, progress=False).model
    same = fit_model("nn", a.displacement, a.force, DT, seed=3, progress=False, **QUICK)
    assert np.array_equal(one.w1, same.w1)
    two = fit([a, b], "nn", QUICK, seed=3, progress=False)
    assert two.model.training["records"] == ["rec0", "rec1"]
    assert two.model.training["input_basis"] == "differences"  # "auto" under free-run
    assert not np.array_equal(two.model.w1, one.w1)
    held = record(3.0, 9)
    assert rms_ratio(held.force, two.model.simulate(held.displacement)) < 0.5


def test_records_at_different_rates_are_refused_naming_both():
    a = record(2.0, 0)
    b = record(2.0, 1, dt=1 / 100.0, name="slow")
    with pytest.raises(IdentificationError, match=r"slow at 100 Hz, rec0 at 204.8 Hz"):
        fit([a, b], "linear", progress=False)


def test_a_record_too_short_for_the_lags_is_refused_naming_it():
    a, short = record(3.0, 0), record(0.3, 1, name="short")
    with pytest.raises(IdentificationError, match="short: record too short for the lags"):
        fit([a, short], "nn", QUICK, progress=False)
    with pytest.raises(IdentificationError, match="rec0: record too short for the lags"):
        fit([a], "nn", dict(QUICK, n_past_x=80), progress=False)


def test_unknown_and_badly_typed_options_are_refused_naming_the_model():
    a = record(2.0, 0)
    with pytest.raises(
        IdentificationError, match=r"unknown options \['generations'\] for model 'nn'"
    ):
        fit([a], "nn", {"generations": 3}, progress=False)
    with pytest.raises(IdentificationError, match="option teacher_lr: 'fast' is not a number"):
        fit([a], "nn", {"teacher_lr": "fast"}, progress=False)
    with pytest.raises(
        IdentificationError, match="recipe must be one of free-run, teacher-forcing"
    ):
        fit([a], "hybrid", {"recipe": "magic"}, progress=False)
    with pytest.raises(IdentificationError, match="no identification for model 'rubber'"):
        fit([a], "rubber", progress=False)


def test_teacher_forcing_recipe_trains_one_step_ahead_only_and_keeps_its_best_check():
    a = record(6.0, 0)
    m = fit([a], "nn", dict(QUICK, recipe="teacher-forcing"), seed=0, progress=False).model
    tr = m.training
    assert tr["recipe"] == "teacher-forcing" and tr["free_run_losses"] == []
    assert tr["input_basis"] == "lags"  # "auto": the papers' network trains on the lags
    history = tr["teacher_validation_mse"]
    assert history and tr["best_teacher_validation_mse"] == min(v for _, v in history)
    assert tr["stopped"].startswith("one step ahead only")


@dataclass(frozen=True)
class OutputBiasToZero:
    """A loss term of the kind issue 17 adds: here, a heavy pull of b_out to 0."""

    weight: float
    name: ClassVar[str] = "b_out_to_zero"
    stages: ClassVar[tuple[str, ...]] = ("teacher", "free-run")

    def __call__(self, net, problem):
        return self.weight * net.b_out**2


def test_a_plugged_in_loss_term_shapes_the_training_and_is_logged():
    a = record(4.0, 0)
    plain = fit([a], "nn", QUICK, seed=1, progress=False).model
    pulled = fit([a], "nn", QUICK, seed=1, progress=False, loss_terms=[OutputBiasToZero(1e3)])
    assert abs(pulled.model.b_out) < 0.1 * abs(plain.b_out)
    assert set(pulled.model.training["loss_terms"]) == {"b_out_to_zero"}
    with pytest.raises(IdentificationError, match="takes no loss terms"):
        fit([a], "linear", progress=False, loss_terms=[OutputBiasToZero(1.0)])


def test_fit_result_records_every_option_and_the_wall_time():
    a = record(2.0, 0)
    res = fit(
        [a],
        "boucwen",
        dict(generations=1, population=2, polish_evaluations=5),
        seed=2,
        progress=False,
    )
    opts = as_dict(res.options)
    assert opts["generations"] == 1 and opts["time_limit_s"] == 0.0
    assert res.seconds > 0 and res.seed == 2 and res.records == [a]


def test_progress_lines_go_to_stderr_with_the_time_left(capsys):
    a = record(4.0, 0)
    fit([a], "nn", dict(QUICK, progress_every_s=0.0), progress=True)
    captured = capsys.readouterr()
    assert captured.out == ""
    assert "s left]" in captured.err and "teacher forcing done" in captured.err
    fit([a], "nn", QUICK, progress=False)
    assert capsys.readouterr().err == ""
    lines = []
    fit([a], "nn", dict(QUICK, progress_every_s=0.0), progress=lines.append)
    assert lines and all(line.startswith("[nn ") for line in lines)


def test_torch_threads_are_restored_after_training():
    before = torch.get_num_threads()
    short = dict(QUICK, threads=2, teacher_steps=10, iters_per_length=(2, 2))
    fit([record(2.0, 0)], "nn", short, progress=False)
    assert torch.get_num_threads() == before
