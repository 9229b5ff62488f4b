"""``scripts/gen_docs.py``: one command rebuilds every generated doc; ``--check`` finds the
stale ones."""

import importlib.util
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "scripts" / "gen_docs.py"


def _gen_docs():
    spec = importlib.util.spec_from_file_location("gen_docs", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    sys.modules["gen_docs"] = module  # its dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def _copy_docs(tmp_path, gen):
    for doc in gen.GENERATED:
        (tmp_path / doc.path).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(ROOT / doc.path, tmp_path / doc.path)


def test_every_generated_doc_of_this_checkout_is_in_step():
    run = subprocess.run(
        [sys.executable, str(SCRIPT), "--check"], capture_output=True, text=True, cwd=ROOT
    )
    assert run.returncode == 0, run.stderr


def test_check_names_the_stale_docs_and_a_run_rewrites_only_the_generated_part(tmp_path, capsys):
    gen = _gen_docs()
    _copy_docs(tmp_path, gen)
    registries = tmp_path / "docs" / "registries.md"
    diagnose = tmp_path / "docs" / "diagnose.md"
    registries.write_text(registries.read_text().replace("| `cma` |", "| `cma-old` |"))
    before = diagnose.read_text()
    diagnose.write_text(before.replace("| inertia | m a,", "| inertia | m times a,"))
    assert gen.main(["--check", "--root", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "docs/registries.md: out of step" in err and "docs/diagnose.md: out of step" in err
    assert gen.main(["--root", str(tmp_path)]) == 0
    assert gen.main(["--check", "--root", str(tmp_path)]) == 0
    assert diagnose.read_text() == before
    assert registries.read_text() == (ROOT / "docs" / "registries.md").read_text()


def test_a_doc_without_its_markers_is_refused_in_one_line(tmp_path, capsys):
    gen = _gen_docs()
    _copy_docs(tmp_path, gen)
    diagnose = tmp_path / "docs" / "diagnose.md"
    diagnose.write_text(diagnose.read_text().replace("<!-- /effects-table -->", ""))
    assert gen.main(["--check", "--root", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (
        "gen_docs: docs/diagnose.md: needs one <!-- effects-table --> and one "
        "<!-- /effects-table --> line around its table"
    )
