"""Identification tests: slow (training) tests run only when asked for, as in tests/rigs."""

import pytest


def pytest_runtest_setup(item):
    if "slow" in item.keywords and "slow" not in (item.config.getoption("-m") or ""):
        pytest.skip("slow test; run with -m slow")
