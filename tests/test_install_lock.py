"""The install is reproducible: the README's commands, CI and the lock agree."""

import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _readme_commands():
    text = (ROOT / "README.md").read_text()
    return [ln for ln in re.findall(r"^pip install torch.*$", text, flags=re.M)]


def _locked():
    pins = {}
    for ln in (ROOT / "constraints.txt").read_text().splitlines():
        if ln.strip() and not ln.startswith("#"):
            name, _, version = ln.partition("==")
            pins[re.sub(r"[-_.]+", "-", name).lower()] = version
    return pins


def test_ci_runs_the_readme_test_command_verbatim():
    tests_cmd = [c for c in _readme_commands() if "pytest" in c]
    assert len(tests_cmd) == 1
    assert tests_cmd[0] in (ROOT / ".ci" / "run").read_text()


def test_both_readme_commands_install_from_the_lock():
    cmds = _readme_commands()
    assert len(cmds) == 2
    for cmd in cmds:
        assert "pip install torch==2.13.0 && pip install -c constraints.txt " in cmd


def test_every_declared_dependency_is_locked():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    declared = list(project["dependencies"])
    for extra in project["optional-dependencies"].values():
        declared += extra
    pins = _locked()
    for req in declared:
        name = re.split(r"[<>=!\[; ]", req, maxsplit=1)[0]
        assert re.sub(r"[-_.]+", "-", name).lower() in pins, f"{name} is not in constraints.txt"
    assert pins["torch"] == "2.13.0"
