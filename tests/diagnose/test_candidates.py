import numpy as np
import pytest

from bushenv.diagnose.candidates import (
    EFFECTS,
    Scales,
    Signals,
    dahl_states,
    get_candidate,
    maxwell_state,
    shift_columns,
)
from bushenv.diagnose.fit import diagnose

from .synthetic import record


@pytest.mark.parametrize("effect", EFFECTS)
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
    sig = Signals(1e-3 * np.sin(np.linspace(0, 20, 400)), 0.01)
    scales = Scales(sigma_x=7e-4, duration_s=4.0, dt=0.01)
    for name in EFFECTS:
        cand = get_candidate(name)
        for shape in cand.shapes(scales):
            cols = cand.columns(sig, shape, scales)
            assert cols.shape == (400, cand.columns_count(shape, scales))
            assert cand.lower(shape, scales).shape == (cols.shape[1],)
            assert np.all(np.isfinite(cols))


def test_unknown_candidate_is_a_clear_error():
    with pytest.raises(ValueError, match="unknown candidate effect 'creep'"):
        get_candidate("creep")


def _fake_identify(monkeypatch, calls):
    import bushenv.identify as identify
    from bushenv.models.linear import LinearBushing

    def fit_model(name, x, f, dt, seed):
        calls.append((name, x.size, dt, seed))
        v = np.gradient(x, dt)
        k, c = np.linalg.lstsq(np.stack([x, v], axis=1), f, rcond=None)[0]
        return LinearBushing(k, c, dt=dt)

    monkeypatch.setattr(identify, "fit_model", fit_model, raising=False)


def test_other_baselines_come_from_the_identify_dispatcher_and_are_augmented(monkeypatch):
    calls = []
    _fake_identify(monkeypatch, calls)
    train = record(8, "inertia", noise=0.002, duration_s=20.0)
    result = diagnose(train, [record(9, "inertia", noise=0.002, name="t")], baseline="boucwen")
    assert calls == [("boucwen", train.force.size, train.dt, 0)]
    assert result["baseline"] == "boucwen"
    assert result["effect"] == "inertia"
    assert result["shrink"] > 0.6


def test_other_baselines_refuse_a_test_at_another_rate(monkeypatch):
    _fake_identify(monkeypatch, [])
    train = record(8, "none", dt=1 / 204.8, duration_s=10.0)
    test = record(9, "none", dt=1 / 512, duration_s=10.0, name="fast")
    with pytest.raises(ValueError, match=r"TEST fast: sampled at 512 Hz but TRAIN at 204\.8 Hz"):
        diagnose(train, [test], baseline="nn")


def test_a_test_equal_to_train_is_flagged_as_not_held_out():
    train = record(10, "none", duration_s=8.0)
    result = diagnose(train, [train], test_names=["same"])
    assert result["notes"] == ["TEST same is the TRAIN record itself: its gap is not held out."]
