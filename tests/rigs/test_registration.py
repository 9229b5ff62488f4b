"""Env specs in envs/: registration with Gymnasium, and shipping them inside the wheel."""

from __future__ import annotations

import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import gymnasium as gym
import pytest
from setuptools import find_namespace_packages

import bushenv
from bushenv.rigs.common import RigError
from bushenv.rigs.registration import register_all
from bushenv.rigs.specs import read_spec, spec_directory, spec_files

ROOT = Path(__file__).resolve().parents[2]
SPEC_IDS = sorted(p.stem for p in (ROOT / "envs").glob("*.toml"))


def test_every_spec_file_is_registered_with_its_kwargs_on_import():
    assert "BushRig-v0" in SPEC_IDS
    for env_id in SPEC_IDS:
        spec = tomllib.loads((ROOT / "envs" / f"{env_id}.toml").read_text())
        for registered in (gym.spec(env_id), gym.spec(f"bushenv/{env_id}")):
            assert registered.entry_point == spec["entry_point"]
            assert registered.kwargs == spec["kwargs"]
            assert registered.vector_entry_point == spec["vector_entry_point"]
            assert registered.max_episode_steps == spec["max_episode_steps"] == 2048
    assert gym.spec("bushenv/BushRig-v0").namespace == "bushenv"
    assert gym.spec("BushRig-v0").vector_entry_point == "bushenv.rigs.vector:BushRigVectorEnv"


def test_the_namespaced_id_makes_in_a_fresh_process_from_another_folder(tmp_path):
    """``gym.make("bushenv:bushenv/<id>")`` imports bushenv itself: no prior import needed."""
    code = (
        "import sys, gymnasium as gym\n"
        "assert 'bushenv' not in sys.modules\n"
        "for env_id in ('BushRig-v0', 'QuarterCar-v0'):\n"
        "    env = gym.make(f'bushenv:bushenv/{env_id}')\n"
        "    obs, info = env.reset(seed=0)\n"
        "    print(env.spec.id, env.spec.max_episode_steps, obs.shape)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.split("\n")[:2] == [
        "bushenv/BushRig-v0 2048 (12,)",
        "bushenv/QuarterCar-v0 2048 (12,)",
    ]


def test_register_all_can_run_twice_and_returns_the_ids():
    assert sorted(register_all()) == SPEC_IDS
    assert sorted(register_all()) == SPEC_IDS


def test_the_specs_found_are_the_envs_folder_of_this_checkout():
    # From a checkout (editable install) they are envs/ itself; from an installed wheel they
    # are its bushenv/envs copy. Either way: the same files with the same contents.
    found = spec_files()
    assert [p.name for p in found] == [f"{i}.toml" for i in SPEC_IDS]
    for p in found:
        assert p.read_text() == (ROOT / "envs" / p.name).read_text()
    assert spec_directory() is not None


def test_a_spec_whose_name_differs_from_its_id_is_refused(tmp_path):
    bad = tmp_path / "Other-v0.toml"
    bad.write_text('id = "BushRig-v0"\nentry_point = "x:y"\nmax_episode_steps = 9\n[kwargs]\n')
    with pytest.raises(RigError, match="does not match"):
        read_spec(bad)
    (tmp_path / "Broken-v0.toml").write_text("id = \n")
    with pytest.raises(RigError, match="not valid TOML"):
        read_spec(tmp_path / "Broken-v0.toml")


@pytest.mark.parametrize(
    ("top", "message"),
    [
        (
            "max_episode_steps = 9\nmax_episode_step = 9",
            r"unknown top-level key\(s\) \['max_episode_step'\]",
        ),
        ("max_episode_steps = 0", "max_episode_steps must be a positive integer, got 0"),
        ("max_episode_steps = 2.5", "max_episode_steps must be a positive integer, got 2.5"),
        ("", "lacks the required key 'max_episode_steps'"),
    ],
)
def test_a_spec_with_an_unknown_key_or_a_bad_episode_length_is_refused(tmp_path, top, message):
    bad = tmp_path / "Some-v0.toml"
    bad.write_text(f'id = "Some-v0"\nentry_point = "x:y"\n{top}\n[kwargs]\n')
    with pytest.raises(RigError, match=message):
        read_spec(bad)


def test_pyproject_lists_every_bushenv_subpackage():
    """setuptools gets an explicit package list (so envs/ can ship as bushenv.envs)."""
    listed = set(
        tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"]
    )
    found = set(find_namespace_packages(where=str(ROOT), include=["bushenv*"]))
    found = {p for p in found if "__pycache__" not in p}
    assert found - listed == set(), "add these to [tool.setuptools] packages in pyproject.toml"
    assert "bushenv.envs" in listed


def _install_like_a_wheel(site: Path) -> None:
    """The installed layout: bushenv/ with the specs as bushenv/envs/ (what the wheel holds)."""
    shutil.copytree(
        Path(bushenv.__file__).parent,
        site / "bushenv",
        ignore=shutil.ignore_patterns("__pycache__", "*.npz", "envs"),
    )
    shutil.copytree(ROOT / "envs", site / "bushenv" / "envs")


def test_an_installed_package_finds_its_specs_through_importlib_resources(tmp_path):
    site = tmp_path / "site"
    _install_like_a_wheel(site)
    code = (
        "import gymnasium as gym, bushenv\n"
        "from bushenv.rigs.specs import spec_files\n"
        "print(spec_files()[0])\n"
        f"print(sorted(k for k in gym.registry if k in {SPEC_IDS!r}))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code],
        cwd=tmp_path,
        env={"PYTHONPATH": str(site), "PATH": "/usr/bin:/bin"},
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    where, ids = out.stdout.strip().splitlines()
    assert Path(where).parent == site / "bushenv" / "envs"
    assert ids == str(SPEC_IDS)


@pytest.mark.slow
def test_built_wheel_contains_the_env_specs(tmp_path):
    src = tmp_path / "src"
    src.mkdir()
    for name in ("pyproject.toml", "README.md"):
        if (ROOT / name).exists():
            shutil.copy(ROOT / name, src / name)
    shutil.copytree(ROOT / "bushenv", src / "bushenv", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(ROOT / "envs", src / "envs")
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            ".",
            "--no-deps",
            "--no-build-isolation",
            "-w",
            str(tmp_path / "dist"),
            "-q",
        ],
        cwd=src,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    (wheel,) = (tmp_path / "dist").glob("bushenv-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    for env_id in SPEC_IDS:
        assert f"bushenv/envs/{env_id}.toml" in names
    assert "bushenv/rigs/registration.py" in names


def test_a_spec_is_parsed_once_per_id_however_many_envs_are_made(monkeypatch):
    from bushenv.rigs import specs

    parsed = []

    def counting(source):
        parsed.append(source.name)
        return read_spec(source)

    monkeypatch.setattr(specs, "read_spec", counting)
    specs.clear_spec_cache()
    for _ in range(3):
        gym.make("BushRig-v0", model="linear").close()
        gym.make("bushenv/BushRig-v0", model="linear", physics_substeps=4).close()
    gym.make("QuarterCar-v0").close()
    assert sorted(parsed) == ["BushRig-v0.toml", "QuarterCar-v0.toml"]


def test_an_env_editing_its_kwargs_leaves_the_next_ones_spec_alone():
    from bushenv.rigs.specs import load_spec, spec_kwargs

    kw = spec_kwargs("QuarterCar-v0", {})
    kw["model"] = "edited"
    load_spec("QuarterCar-v0")["kwargs"]["reference"] = "edited"
    again = load_spec("QuarterCar-v0")["kwargs"]
    assert again["model"] == "linear" and again["reference"] == "rubber"
