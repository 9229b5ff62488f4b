"""Shared set-up for the rig tests: headless drawing, env registration, fixtures."""

from __future__ import annotations

import os

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

import pytest  # noqa: E402
from rig_test_models import NanAfter  # noqa: E402

import bushenv  # noqa: E402,F401  (registers the envs)


@pytest.fixture
def nan_model():
    return NanAfter(after=5)


def pytest_runtest_setup(item):
    # Slow tests run only when asked for: pytest -m slow
    if "slow" in item.keywords and "slow" not in (item.config.getoption("-m") or ""):
        pytest.skip("slow test; run with -m slow")
