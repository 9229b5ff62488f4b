import json
import subprocess
import sys

import pytest

from bushenv.cli import main
from bushenv.models.linear import LinearBushing

from .conftest import fold_hybrid

# the test models are files without a model card: the stroke is given (the papers' 12.5 mm)
FAST = ["--holds", "9", "--passivity-mm", "0", "--energy-mm", "1", "--stroke-mm", "12.5", "--quiet"]


def _one_error_line(capsys, code):
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and err[0].startswith("bushenv certify: error:")
    return err[0]


def test_certify_writes_the_certificate_and_plots(tmp_path, capsys):
    model = fold_hybrid().save(tmp_path / "fold.npz")
    out = tmp_path / "cert"
    code = main(["certify", str(model), "--reference", "linear", "--out", str(out), *FAST])
    doc = json.loads((out / "certificate.json").read_text())
    s = doc["summary"]  # exits as a test runner: 0 passes, 1 fails
    assert code == (0 if s["passes_holds"] and s["passes_passivity"] else 1)
    assert len(doc["holds"]) == 9
    assert doc["model"]["name"] == "hybrid" and doc["reference"]["source"] == "linear"
    for png in ("static_force.png", "spectral_radius.png", "passivity.png"):
        assert (out / png).stat().st_size > 10_000
    printed = capsys.readouterr()
    assert "holds: 9" in printed.out and printed.err == ""  # --quiet
    # a second run refuses to overwrite without --force
    code = main(["certify", str(model), "--reference", "linear", "--out", str(out), *FAST])
    assert "exists; pass --force" in _one_error_line(capsys, code)


def test_progress_goes_to_stderr_with_stages(tmp_path, capsys):
    model = fold_hybrid().save(tmp_path / "fold.npz")
    code = main(["certify", str(model), "--out", str(tmp_path / "c"), *FAST[:-1]])
    assert code in (0, 1)
    err = capsys.readouterr().err
    for stage in ("fixed points", "free runs", "reference holds", "passivity", "energy scan"):
        assert stage in err


def test_a_model_that_is_not_narx_is_refused_naming_its_class(tmp_path, capsys):
    path = LinearBushing.preset("axial").save(tmp_path / "lin.npz")
    code = main(["certify", str(path), "--out", str(tmp_path / "c")])
    line = _one_error_line(capsys, code)
    assert "LinearBushing" in line and "nn, hybrid" in line
    code = main(["certify", "boucwen", "--out", str(tmp_path / "c")])
    assert "BoucWenBushing" in _one_error_line(capsys, code)
    assert not (tmp_path / "c").exists()


@pytest.mark.parametrize(
    "args,needle",
    [
        (["no/such/model.npz"], "no such model file"),
        (["nn", "--holds", "2"], "--holds must be >= 3"),
        (["nn", "--reference", "nope.npz"], "no such model file"),
        (["nn", "--stroke-mm", "-1"], "stroke_m must be a positive"),
    ],
)
def test_bad_input_exits_2_with_one_line(tmp_path, capsys, args, needle):
    code = main(["certify", *args, "--out", str(tmp_path / "c"), "--quiet"])
    assert needle in _one_error_line(capsys, code)


def test_help_shows_every_option_with_its_default():
    proc = subprocess.run(
        [sys.executable, "-m", "bushenv.cli", "certify", "--help"], capture_output=True, text=True
    )
    assert proc.returncode == 0
    text = " ".join(proc.stdout.split())
    for opt in (
        "--reference",
        "--axis",
        "--holds",
        "--stroke-mm",
        "--hold-s",
        "--velocity",
        "--passivity-mm",
        "--sine-mm",
        "--energy-mm",
        "--out",
        "--force",
        "--quiet",
    ):
        assert opt in text
    for default in (
        "(default: rubber for a registered model",
        "(default: axial)",
        "(default: 201)",
        "(default: the model card's stroke",
        "(default: 20)",
        "(default: central)",
        "(default: -4,-1,0,1,4)",
        "(default: 0.1)",
        "(default: 0.25,0.5,1,2)",
    ):
        assert default in text, default
    assert "example:" in text and "bushenv certify" in text
