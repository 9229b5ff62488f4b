"""Behaviour unchanged: the main outputs equal the golden files recorded before the refactor.

Every value must match: strings, booleans and integers exactly, floats to 1e-9 relative (the
kernels give the same bits on one machine; the tolerance only absorbs another CPU's libm).
The RL searches train torch networks, whose sums another CPU's kernels order differently:
their run's floats match to ``RL_RTOL`` (measured 6.5e-8 between two machines), every verdict
and count still exactly.
"""

from __future__ import annotations

import json
import math

import pytest

from .runs import RUNS, golden_path, normalised

FLOAT_RTOL = 1e-9
RL_RTOL = 1e-6
TOLERANCE = {"attack_rl": RL_RTOL}  # per golden run; FLOAT_RTOL for the others


def differences(want, got, where="$", rtol=FLOAT_RTOL):
    """Paths at which ``got`` differs from ``want``, with both values."""
    if isinstance(want, dict) and isinstance(got, dict):
        out = [f"{where}: key only in golden: {k}" for k in want.keys() - got.keys()]
        out += [f"{where}: key only in new run: {k}" for k in got.keys() - want.keys()]
        for k in want.keys() & got.keys():
            out += differences(want[k], got[k], f"{where}.{k}", rtol)
        return out
    if isinstance(want, list) and isinstance(got, list):
        if len(want) != len(got):
            return [f"{where}: {len(want)} items in golden, {len(got)} now"]
        pairs = enumerate(zip(want, got, strict=True))
        return [d for i, (a, b) in pairs for d in differences(a, b, f"{where}[{i}]", rtol)]
    if isinstance(want, float) and isinstance(got, float | int) and not isinstance(got, bool):
        if math.isclose(want, got, rel_tol=rtol, abs_tol=1e-12):
            return []
        return [f"{where}: golden {want!r}, now {got!r}"]
    if want != got or type(want) is not type(got):
        return [f"{where}: golden {want!r}, now {got!r}"]
    return []


@pytest.mark.parametrize("name", sorted(RUNS))
def test_output_equals_the_golden_file(name, tmp_path):
    want = json.loads(golden_path(name).read_text())
    got = normalised(RUNS[name](tmp_path))
    problems = differences(want, got, rtol=TOLERANCE.get(name, FLOAT_RTOL))
    assert not problems, "\n".join(problems[:40])


def test_differences_sees_a_changed_float_a_missing_key_and_a_flipped_verdict():
    want = {"a": 1.0, "b": {"diverged": True}, "c": [1, 2]}
    assert differences(want, {"a": 1.0, "b": {"diverged": True}, "c": [1, 2]}) == []
    assert differences(want, {"a": 1.0 + 1e-6, "b": {"diverged": True}, "c": [1, 2]})
    assert differences(want, {"a": 1.0, "b": {}, "c": [1, 2]})
    assert differences(want, {"a": 1.0, "b": {"diverged": False}, "c": [1, 2]})
    assert differences(want, {"a": 1.0, "b": {"diverged": True}, "c": [1]})
    rl = {"a": 1.0 + 1e-7, "b": {"diverged": True}, "c": [1, 2]}
    assert differences(want, rl) and not differences(want, rl, rtol=RL_RTOL)
    assert differences(want, {**rl, "a": 1.0 + 1e-5}, rtol=RL_RTOL)
