"""Every registered effect through every check of the effect contract
(``bushenv.diagnose.checks``): registering an effect is the one step that tests it."""

import json

import numpy as np
import pytest

from bushenv.cli import main
from bushenv.diagnose.candidates import EFFECTS, EffectContractError, effect_names
from bushenv.diagnose.checks import CHECKS, check_effect
from bushenv.diagnose.effects.base import Effect

from .synthetic import record
from .test_report import write_csv


@pytest.mark.parametrize("check", list(CHECKS))
@pytest.mark.parametrize("name", effect_names())
def test_every_registered_effect_keeps_the_contract(name, check):
    CHECKS[check](name)


class Preload(Effect):
    """A constant force (a preloaded mount): one weight of either sign (a test effect)."""

    name = "preload"
    form = "F_0"
    weights = "F_0 free (N)"

    def columns(self, s, shape, scales):
        return np.ones((s.x.size, 1))

    def lower(self, shape, scales):
        return np.full(1, -np.inf)

    def example(self, scales, k_n_per_m):
        return None, np.array([0.5 * k_n_per_m * scales.sigma_x])


def preloaded_record(seed, name=""):
    rec = record(seed, "none", noise=0.002, duration_s=12.0, name=name)
    rec.force = rec.force + 0.5 * 380e3 * 1e-3
    return rec


def test_an_effect_registered_at_run_time_is_checked_and_accepted_by_the_cli(tmp_path):
    with EFFECTS.temporarily("preload", Preload):
        assert "preload" in effect_names()
        check_effect("preload")
        train = write_csv(tmp_path / "train.csv", preloaded_record(3))
        test = write_csv(tmp_path / "test.csv", preloaded_record(4))
        out = tmp_path / "out"
        args = ["diagnose", str(train), str(test), "--out", str(out), "--quiet"]
        assert main(args + ["--effects", "preload,relaxation"]) == 0
    report = json.loads((out / "report.json").read_text())
    assert {r["effect"] for r in report["ranking"]} == {"preload", "relaxation"}
    assert report["effect"] == "preload"
    assert "preload" not in effect_names()


def test_a_columns_count_kept_by_hand_out_of_step_fails_the_checks():
    class Forgetful(Preload):
        name = "forgetful"

        def columns_count(self, shape, scales):
            return 0  # the old silent default: the effect would add no columns

    with EFFECTS.temporarily("forgetful", Forgetful):
        with pytest.raises(AssertionError, match="forgetful at None: columns .* says 0"):
            CHECKS["columns_shape_and_finite"]("forgetful")


def test_the_derived_columns_count_follows_the_columns():
    with EFFECTS.temporarily("preload", Preload):
        from bushenv.diagnose.candidates import get_effect
        from bushenv.diagnose.checks import probes

        assert get_effect("preload").columns_count(None, probes()[1]) == 1


def test_registration_refuses_a_second_name_an_incomplete_effect_and_a_reserved_name():
    class NoExample(Effect):
        name = "noexample"
        form = weights = "x"

        def columns(self, s, shape, scales):
            return s.x[:, None]

    with pytest.raises(EffectContractError, match="declares name 'preload'"):
        EFFECTS.add("preload2", Preload)
    with pytest.raises(EffectContractError, match="does not implement example"):
        EFFECTS.add("noexample", NoExample)
    with pytest.raises(EffectContractError, match="not an Effect subclass"):
        EFFECTS.add("thing", dict)
    none = type("NoneEffect", (Preload,), {"name": "none"})
    with pytest.raises(EffectContractError, match="not 'none'"):
        EFFECTS.add("none", none)
    assert "preload2" not in EFFECTS and "noexample" not in EFFECTS and "none" not in EFFECTS


def test_a_forward_form_its_regressors_cannot_reproduce_fails_the_checks():
    class Lagless(Preload):
        """Claims a delay its forward form does not apply."""

        name = "lagless"

        def delay_s(self, shape):
            return 0.004

        def forward(self, s, force, shape, w, scales):
            return force + self.columns(s, shape, scales) @ w

    with EFFECTS.temporarily("lagless", Lagless):
        with pytest.raises(AssertionError, match="lagless: its regressors leave"):
            CHECKS["forward_recovers_its_parameters"]("lagless")


class DriftingPreload(Preload):
    """A preload whose richest form lets it drift linearly through a record; both weights of
    either sign, declared for the richest form in ``rich_lower`` (a test effect)."""

    name = "driftingpreload"

    def rich_columns(self, s, shape, scales):
        ramp = np.arange(s.x.size) / s.x.size
        return np.stack([np.ones(s.x.size), ramp], axis=1)

    def rich_lower(self, shape, scales):
        return np.full(2, -np.inf)


def test_the_richest_form_is_bounded_by_rich_lower_and_a_miscount_fails_the_checks():
    from bushenv.diagnose.candidates import get_effect
    from bushenv.diagnose.checks import probes
    from bushenv.diagnose.effects.base import Lasting, Nuisance, Richest

    scales = probes()[1]
    with EFFECTS.temporarily("driftingpreload", DriftingPreload):
        check_effect("driftingpreload")
        effect = get_effect("driftingpreload")
        assert list(effect.block_lower(Richest(None), scales)) == [-np.inf, -np.inf]
        assert list(effect.block_lower(Lasting(None), scales)) == [-np.inf, 0.0, 0.0, 0.0]
        assert effect.block_lower(Nuisance(None), scales).shape == (0,)

    class Miscounted(DriftingPreload):
        name = "miscounted"

        def rich_lower(self, shape, scales):
            return np.full(1, -np.inf)  # the usual form's count

    with EFFECTS.temporarily("miscounted", Miscounted):
        with pytest.raises(AssertionError, match=r"miscounted at Richest.*\(1,\) bounds for 2"):
            CHECKS["other_forms"]("miscounted")


def test_an_effect_lower_is_asked_about_its_usual_shapes_only():
    """A ``lower`` that reads its shape (a tuple here) never sees the diagnosis's markers."""
    from bushenv.diagnose.candidates import get_effect
    from bushenv.diagnose.checks import probes
    from bushenv.diagnose.effects.base import Lasting, Nuisance, Richest

    class Tupled(Preload):
        name = "tupled"

        def shapes(self, scales):
            return [("free", 1.0), ("signed", 2.0)]

        def lower(self, shape, scales):
            kind, _ = shape  # a marker here would raise
            return np.full(1, -np.inf if kind == "free" else 0.0)

        def example(self, scales, k_n_per_m):
            return ("free", 1.0), np.array([0.5 * k_n_per_m * scales.sigma_x])

    scales = probes()[1]
    with EFFECTS.temporarily("tupled", Tupled):
        CHECKS["other_forms"]("tupled")
        CHECKS["bounds_admissible"]("tupled")
        effect = get_effect("tupled")
        for marker in (Richest, Lasting):
            assert effect.block_lower(marker(("signed", 2.0)), scales)[0] == 0.0
        assert effect.block_lower(Nuisance(("free", 1.0)), scales).shape == (0,)
