"""Registries are the only lists: an entry added at run time is accepted by the CLI and
listed in the docs page generated from them."""

import json
from pathlib import Path

from bushenv.cli import main
from bushenv.models import MODELS, ModelEntry
from bushenv.models.linear import LinearBushing
from bushenv.registries import markdown
from bushenv.search.searchers import SEARCHERS, RandomSearch, SearcherEntry

DOCS = Path(__file__).resolve().parents[1] / "docs" / "registries.md"


class Soft(LinearBushing):
    name = "soft"

    @classmethod
    def preset(cls, axis="axial", dt=1 / 204.8):
        return cls(k_n_per_m=2e5, c_ns_per_m=2e3, dt=dt)


class Steps(RandomSearch):
    name = "steps"

    def __init__(self):
        super().__init__(families=("step",), batch_size=8)


def test_the_docs_page_is_what_the_registries_hold():
    assert DOCS.read_text() == markdown(), "rerun: python scripts/gen_docs.py"


def test_a_searcher_and_a_model_registered_at_run_time_are_accepted_by_attack(tmp_path, capsys):
    with (
        SEARCHERS.temporarily("steps", SearcherEntry(Steps, "steps only")),
        MODELS.temporarily("soft", ModelEntry(Soft, "a soft linear bushing")),
    ):
        out = tmp_path / "run"
        argv = ["attack", "--model", "soft", "--searchers", "steps", "--budget", "8"]
        assert main([*argv, "--out", str(out), "--no-plots", "--quiet"]) == 0
        report = json.loads((out / "report.json").read_text())
        assert report["models"]["soft"]["searchers"]["steps"]["evaluations"] == 8
        assert "| `steps` |" in markdown() and "| `soft` |" in markdown()
    assert "steps" not in SEARCHERS and "soft" not in MODELS


def test_the_campaign_matrix_accepts_a_model_registered_at_run_time(tmp_path, capsys):
    with MODELS.temporarily("soft", ModelEntry(Soft, "a soft linear bushing")):
        out = tmp_path / "m"
        argv = ["campaign", "--models", "soft", "--searchers", "random", "--seeds", "0"]
        assert main([*argv, "--budget", "8", "--out", str(out), "--workers", "1"]) == 0
    assert "soft" in (out / "summary.md").read_text()


def test_unknown_names_are_refused_naming_every_registered_one(tmp_path, capsys):
    argv = ["attack", "--searchers", "nope", "--budget", "8", "--out", str(tmp_path / "x")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    for name in SEARCHERS.names():
        assert name in err
