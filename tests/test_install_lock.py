"""The install is reproducible: the README's commands, CI and the lock agree."""

import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _readme_commands():
    text = (ROOT / "README.md").read_text()
    return [ln for ln in re.findall(r"^pip install .*torch==.*$", text, flags=re.M)]


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
        # both steps through the lock: torch's own dependencies too (sympy, setuptools, ...)
        assert cmd.startswith("pip install -c constraints.txt torch==2.13.0 && ")
        assert " && pip install -c constraints.txt " in cmd


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


def test_everything_the_package_pulls_in_is_locked():
    # walk the installed dependency closure of bushenv[test,ray,fmi]: every distribution a
    # fresh install brings must have its version fixed by the lock
    from importlib import metadata

    from packaging.requirements import Requirement

    pins = _locked()
    seen, todo, missing = set(), [("bushenv", {"test", "ray", "fmi"})], []
    while todo:
        name, extras = todo.pop()
        key = re.sub(r"[-_.]+", "-", name).lower()
        if (key, frozenset(extras)) in seen:
            continue
        seen.add((key, frozenset(extras)))
        try:
            dist = metadata.distribution(name)
        except metadata.PackageNotFoundError:
            continue  # not installed here (a marker for another platform)
        # pip comes with the venv itself (ensurepip's, fixed per Python release)
        if key not in ("bushenv", "pip", "wheel") and key not in pins:
            missing.append(key)
        for text in dist.requires or []:
            req = Requirement(text)
            envs = [{"extra": e} for e in extras] or [{"extra": ""}]
            if req.marker is None or any(req.marker.evaluate(env) for env in envs):
                todo.append((req.name, set(req.extras)))
    assert not missing, f"installed but not locked in constraints.txt: {sorted(set(missing))}"
