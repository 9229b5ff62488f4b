import numpy as np
import pytest

from bushenv.diagnose.candidates import (
    EFFECTS,
    UnknownEffectError,
    candidate_sets,
    effect_names,
    get_effect,
)
from bushenv.diagnose.effects.base import NULL, Scales, Signals
from bushenv.diagnose.effects.friction import Friction, dahl_states
from bushenv.diagnose.effects.relaxation import Relaxation, maxwell_state
from bushenv.diagnose.effects.timeshift import shift_columns
from bushenv.diagnose.fit import diagnose

from .synthetic import record


@pytest.mark.parametrize("effect", list(EFFECTS))
def test_each_candidate_recovers_its_own_effect_on_clean_synthetic_data(effect):
    train = record(1, effect, noise=0.002, duration_s=24.0)
    tests = [record(2, effect, noise=0.002, duration_s=24.0, name="t")]
    result = diagnose(train, tests)
    assert result["effect"] == effect
    assert result["ranking"][0]["effect"] == effect
    assert result["shrink"] > 0.6


def test_purely_linear_record_names_none():
    train = record(3, "none", noise=0.01)
    tests = [record(4, "none", noise=0.01, name="a"), record(5, "none", noise=0.01, name="b")]
    result = diagnose(train, tests)
    assert result["effect"] == "none"
    assert result["gap_after"] == result["gap_before"]
    assert all(r["shrink"] < 0.05 for r in result["ranking"])


def test_linear_baseline_handles_a_test_at_another_sample_rate():
    train = record(6, "relaxation", noise=0.002, dt=1 / 204.8)
    test = record(7, "relaxation", noise=0.002, dt=1 / 1024, duration_s=15.0, name="fast")
    result = diagnose(train, [test])
    assert result["effect"] == "relaxation"
    assert result["records"]["tests"][0]["rate_hz"] == pytest.approx(1024)
    assert result["shrink"] > 0.6


def test_maxwell_state_of_a_ramp_matches_the_exact_solution():
    dt, tau, rate = 1e-3, 0.05, 0.01
    t = np.arange(2000) * dt
    h = maxwell_state(rate * t, dt, tau)
    exact = rate * tau * (1 - np.exp(-t / tau))  # h' = v - h / tau from rest
    assert np.max(np.abs(h - exact)) < 1e-3 * rate * tau


def test_dahl_states_saturate_at_one_and_are_rate_independent():
    x = 1e-3 * np.sin(np.linspace(0, 6 * np.pi, 3000))
    xs = np.array([1e-5, 1e-4])
    fast = np.empty((3000, 2))
    dahl_states(x, xs, fast)
    slow = np.empty((6000, 2))
    dahl_states(np.repeat(x, 2), xs, slow)
    assert np.all(np.abs(fast) <= 1.0)
    assert np.max(fast[:, 0]) > 0.999
    assert np.allclose(fast[-1], slow[-1])


def test_shift_columns_delays_by_whole_samples_exactly():
    cols = np.arange(20.0)[:, None]
    out = shift_columns(cols, 3 * 0.01, 0.01)
    assert np.allclose(out[3:, 0], cols[:-3, 0])


def test_candidate_columns_have_one_weight_bound_each():
    x = 1e-3 * np.sin(np.linspace(0, 20, 400))
    sig = Signals(x, 0.01)
    scales = Scales.of([sig])
    for name in effect_names():
        cand = get_effect(name)
        for shape in cand.shapes(scales):
            cols = cand.columns(sig, shape, scales)
            assert cols.shape == (400, cand.columns_count(shape, scales))
            assert cand.lower(shape, scales).shape == (cols.shape[1],)
            assert np.all(np.isfinite(cols))


def test_unknown_candidate_is_a_clear_error_listing_the_registry():
    with pytest.raises(UnknownEffectError, match="unknown candidate effect 'nosuch'; known: "):
        get_effect("nosuch")
    with pytest.raises(ValueError, match=", ".join(effect_names())):
        get_effect("nosuch")


def test_effects_compose_with_plus_and_refuse_a_duplicate():
    combo = Relaxation() + Friction()
    assert combo.name == "relaxation+friction"
    assert combo.names == ("relaxation", "friction")
    assert (NULL + Relaxation()).name == "relaxation"
    with pytest.raises(ValueError, match="added twice"):
        combo + Relaxation()


def test_candidate_sets_are_every_single_and_every_pair_of_the_registry():
    sets = candidate_sets()
    n = len(EFFECTS)
    assert len(sets) == n + n * (n - 1) // 2
    assert [s.name for s in sets[:n]] == list(effect_names())


def _fake_identify(monkeypatch, calls):
    import bushenv.identify as identify
    from bushenv.models.linear import LinearBushing

    def fit_model(name, x, f, dt, seed, progress=True):
        calls.append((name, x.size, dt, seed))
        progress("epoch 1/1")  # a training line: the diagnosis's own progress gets it
        v = np.gradient(x, dt)
        k, c = np.linalg.lstsq(np.stack([x, v], axis=1), f, rcond=None)[0]
        return LinearBushing(k, c, dt=dt)

    monkeypatch.setattr(identify, "fit_model", fit_model, raising=False)


def test_other_baselines_come_from_the_identify_dispatcher_and_are_augmented(monkeypatch):
    calls, lines = [], []
    _fake_identify(monkeypatch, calls)
    train = record(8, "inertia", noise=0.002, duration_s=20.0)
    test = record(9, "inertia", noise=0.002, name="t")
    result = diagnose(train, [test], baseline="boucwen", progress=lines.append)
    assert "epoch 1/1" in lines  # so --quiet (no progress) silences the training too
    assert calls == [("boucwen", train.force.size, train.dt, 0)]
    assert result["baseline"] == "boucwen"
    assert result["effect"] == "inertia"
    assert result["shrink"] > 0.6


def test_other_baselines_refuse_a_test_at_another_rate_and_the_cross_mode(monkeypatch):
    _fake_identify(monkeypatch, [])
    train = record(8, "none", dt=1 / 204.8, duration_s=10.0)
    test = record(9, "none", dt=1 / 512, duration_s=10.0, name="fast")
    with pytest.raises(ValueError, match=r"fast: sampled at 512 Hz but TRAIN at 204\.8 Hz"):
        diagnose(train, [test], baseline="nn")
    same = record(10, "none", duration_s=10.0, name="t")
    with pytest.raises(ValueError, match="only the linear baseline"):
        diagnose(train, [same], baseline="nn", cross=True)


def test_a_test_equal_to_train_is_flagged_as_not_held_out():
    train = record(10, "none", duration_s=8.0)
    result = diagnose(train, [train], test_names=["same"])
    assert (
        "TEST same is the TRAIN record rec10 itself: its gap is not held out." in (result["notes"])
    )


def test_a_force_channel_lag_is_seen_by_its_phase_and_a_relaxation_is_not():
    from bushenv.diagnose.lag import lag_evidence

    def evidence(effect):
        recs = [record(s, effect, noise=0.005, duration_s=20.0) for s in (1, 2)]
        return lag_evidence([(r.name, r.displacement, r.force, r.dt) for r in recs])

    lagged = evidence("delay")
    # the passive family takes up part of a lag (a smaller damper): what is left is a lower
    # bound of the 6 ms
    assert lagged.seen and 0.003 < lagged.delay_s <= 0.0066
    for effect in ("none", "relaxation", "thermal", "inertia", "hardening"):
        assert not evidence(effect).seen, effect


def test_fitted_spring_damper_and_mass_stay_physical_on_a_lagged_force():
    train = record(1, "delay", noise=0.002, duration_s=20.0)
    result = diagnose(train, [record(2, "delay", noise=0.002, name="t")], effects=["inertia"])
    params = result["parameters"]
    assert params["c_ns_per_m"] >= 0 and params["k_n_per_m"] >= 0
    assert params.get("inertia", {"mass_kg": 0.0})["mass_kg"] >= 0
    assert result["effect"] in ("none", "outside_candidates", "inertia")


def test_the_runner_up_is_another_candidate_than_the_answer():
    train = record(1, "relaxation", noise=0.002, duration_s=24.0)
    result = diagnose(train, [record(2, "relaxation", noise=0.002, duration_s=24.0, name="t")])
    assert result["effect"] == "relaxation"
    assert result["runner_up"] not in (None, "relaxation")


def test_the_column_store_keeps_its_budget_and_gives_the_same_columns_after_eviction(monkeypatch):
    """A refined leak visits many shapes once: columns beyond the budget go, least recently
    used first, and come back identical when asked again."""
    from bushenv.diagnose import design
    from bushenv.diagnose.design import ColumnStore, Prepared

    dt = 1 / 200.0
    x = 2e-3 * np.sin(2 * np.pi * 1.5 * np.arange(4000) * dt)
    s = Signals(x, dt)
    prep = Prepared("r", "train", np.arange(x.size) * dt, s, x * 1e5, np.zeros(x.size))
    store = ColumnStore(Scales.of([s]))
    blocks = [("thermal", ("viscous", float(tau))) for tau in (20, 30, 40, 50, 60)]
    monkeypatch.setattr(design, "COLUMNS_KEPT_BYTES", 3 * x.size * 2 * 8)  # three blocks
    first = store.columns(prep, blocks[0]).copy()
    for b in blocks[1:]:
        store.columns(prep, b)
    assert store._cols_bytes <= design.COLUMNS_KEPT_BYTES
    assert (prep.uid, blocks[0]) not in store._cols  # the oldest went first
    assert (prep.uid, blocks[-1]) in store._cols
    assert np.array_equal(store.columns(prep, blocks[0]), first)
