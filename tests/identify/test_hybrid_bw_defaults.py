"""hybrid-bw's defaults since the combined programme's remainder re-measure
(studies/2026-11-combined-programme): a quasi-linear backbone relaxation and a remainder network
whose free run is long enough to change the weights kept; flags given still win, and the
three-axis ``boucwen`` kind keeps the constant form."""

import numpy as np

from bushenv.identify import fit, options_class
from bushenv.identify.boucwen_options import VectorBoucWenOptions
from bushenv.identify.mimo import HYBRID_BW_FREE_RUN_STEPS, HybridBWOptions
from bushenv.identify.mimo_options import MimoOptions
from bushenv.identify.options import options_of
from bushenv.models.base import PAPER_DT
from bushenv.motions import random_correlated
from bushenv.reference.planar import PlanarRubber


def test_hybrid_bw_defaults_to_qlv_and_a_long_free_run():
    opts = options_class("hybrid-bw", 3)()
    assert opts.relaxation_form == "qlv" and opts.backbone_options().relaxation_form == "qlv"
    assert opts.free_run_steps == HYBRID_BW_FREE_RUN_STEPS > MimoOptions().free_run_steps
    assert opts.train_options().free_run_steps == HYBRID_BW_FREE_RUN_STEPS
    # the other kinds keep theirs
    assert options_class("boucwen", 3)().relaxation_form == "constant"
    assert VectorBoucWenOptions().relaxation_form == "constant"
    assert options_class("hybrid", 3)().free_run_steps == MimoOptions().free_run_steps


def test_flags_given_win_over_hybrid_bw_defaults():
    given = {"relaxation_form": "constant", "free_run_steps": 200}
    opts = options_of(HybridBWOptions, given, "hybrid-bw")
    assert opts.backbone_options().relaxation_form == "constant"
    assert opts.train_options().free_run_steps == 200


def test_a_hybrid_bw_fit_without_the_setting_has_a_qlv_backbone(tmp_path):
    from bushenv.models.files import load_model

    q = random_correlated(1.0, 8.0, PAPER_DT, 5)
    f = PlanarRubber.preset(seed=5).simulate(q)
    short = {"evaluations": 2, "hidden": 9, "teacher_steps": 20, "free_run_steps": 5,
             "windows": 4, "window": 32, "relaxation_times": "0.03,0.3"}  # fmt: skip
    model = fit([(q, f)], "hybrid-bw", short, 0, False, dt=PAPER_DT).model
    assert model.backbone.relaxation_form == "qlv"
    back = load_model(model.save(tmp_path / "m.npz"))
    assert back.backbone.relaxation_form == "qlv"
    np.testing.assert_array_equal(back.simulate(q), model.simulate(q))
