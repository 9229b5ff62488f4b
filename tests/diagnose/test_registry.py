"""The effects registry is the only list: a dummy effect added at run time is tried, named,
accepted by the CLI and listed in the docs table."""

import json

import numpy as np
import pytest

from bushenv.cli import main
from bushenv.diagnose import candidates
from bushenv.diagnose.candidates import EFFECTS, effects_table
from bushenv.diagnose.effects.base import Effect
from bushenv.diagnose.fit import diagnose

from .synthetic import record
from .test_report import write_csv

HUM_HZ = 3.0


class Hum(Effect):
    """A force at a fixed frequency whatever the motion (a test effect)."""

    name = "hum"
    form = "a sin(2 pi 3 t) + b cos(2 pi 3 t)"
    weights = "free (N)"

    def columns(self, s, shape, scales):
        t = np.arange(s.x.size) * s.dt
        return np.stack([np.sin(2 * np.pi * HUM_HZ * t), np.cos(2 * np.pi * HUM_HZ * t)], axis=1)

    def lower(self, shape, scales):
        return np.full(2, -np.inf)

    def example(self, scales, k_n_per_m):
        return None, np.array([0.1 * k_n_per_m * scales.sigma_x, 0.0])


def hum_record(seed, name=""):
    rec = record(seed, "none", noise=0.002, duration_s=15.0, name=name)
    t = rec.time
    rec.force = rec.force + 0.1 * np.std(rec.force) * np.sin(2 * np.pi * HUM_HZ * t + 0.3)
    return rec


@pytest.fixture
def with_hum():
    with EFFECTS.temporarily("hum", Hum):
        yield Hum


def test_a_dummy_effect_added_at_run_time_is_tried_and_named(with_hum):
    result = diagnose(hum_record(1), [hum_record(2, "t")])
    assert "hum" in [r["effect"] for r in result["ranking"]]
    assert any("hum" in r["members"] for r in result["pairs"])
    assert result["effect"] == "hum"
    assert result["shrink"] > 0.8


def test_the_cli_accepts_a_registered_effect_and_lists_it(with_hum, tmp_path, capsys):
    train = write_csv(tmp_path / "train.csv", hum_record(3))
    test = write_csv(tmp_path / "test.csv", hum_record(4))
    out = tmp_path / "out"
    args = ["diagnose", str(train), str(test), "--out", str(out), "--quiet"]
    assert main(args + ["--effects", "hum,relaxation"]) == 0
    report = json.loads((out / "report.json").read_text())
    assert [r["effect"] for r in report["ranking"]][0] == "hum"
    assert {r["effect"] for r in report["ranking"]} == {"hum", "relaxation"}
    with pytest.raises(SystemExit):
        main(["diagnose", "--help"])
    assert "hum" in capsys.readouterr().out
    assert "| hum |" in effects_table()


def test_an_unknown_effect_on_the_command_line_names_the_known_ones(tmp_path, capsys):
    train = write_csv(tmp_path / "train.csv", record(5, "none", duration_s=5.0))
    code = None
    with pytest.raises(SystemExit) as exc:
        main(
            [
                "diagnose",
                str(train),
                str(train),
                "--out",
                str(tmp_path / "o"),
                "--effects",
                "nosuch",
            ]
        )
    code = exc.value.code
    assert code == 2
    err = capsys.readouterr().err
    assert "nosuch" in err and ", ".join(candidates.effect_names()) in err
