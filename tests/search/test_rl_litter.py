"""The RL searchers leave nothing behind: no logger folder in the system temp folder."""

import tempfile
from pathlib import Path

from bushenv.models import get_model, get_reference
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.searchers import get_searcher


def test_ppo_and_sac_write_no_logger_folder(tmp_path, monkeypatch):
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    tempfile.tempdir = None  # re-read TMPDIR
    try:
        model = get_model("linear", axis="axial")
        reference = get_reference("rubber", axis="axial", dt=model.dt)
        for name in ("ppo", "sac"):
            with BatchEvaluator(model, reference, "rig") as ev:
                get_searcher(name).run(ev, 4, seed=0)
    finally:
        tempfile.tempdir = None
    assert not [p.name for p in Path(tmp_path).iterdir() if p.name.startswith("SB3")]
