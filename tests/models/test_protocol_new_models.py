"""The shipped nn, hybrid and boucwen: damaged files refused, model-specific refusals.

The protocol itself (reruns, batching, copies, save/load) is checked over every registered
model by ``test_registry_checks.py``; a shape the registry does not ship is checked here."""

import json

import numpy as np
import pytest

from bushenv.models import ModelError, get_model, load_model
from bushenv.models.boucwen import BoucWenBushing
from bushenv.models.checks import CHECKS
from bushenv.models.narx import NarxBushing


def make_nn(hidden=(9,)):
    return NarxBushing.initialised((-0.002, 0.002), (-900.0, 1100.0), hidden=hidden, seed=3)


@pytest.mark.parametrize("check", sorted(CHECKS))
def test_a_two_layer_network_keeps_the_contract(check):
    # the registry's checks run the shipped networks (one hidden layer); this shape too
    CHECKS[check](lambda: make_nn((10, 9)))


@pytest.mark.parametrize("kind", ["nn", "hybrid"])
def test_load_refuses_inconsistent_network_shapes_naming_the_file(kind, tmp_path):
    path = get_model(kind).save(tmp_path / "net.npz")
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays.pop("__meta__")))
    arrays["w1"] = arrays["w1"][:, :-1]  # one input short
    meta["shapes"]["w1"] = list(arrays["w1"].shape)
    np.savez(tmp_path / "short.npz", __meta__=np.array(json.dumps(meta)), **arrays)
    with pytest.raises(ModelError, match=r"short\.npz.*'w1'.*shape"):
        load_model(tmp_path / "short.npz")


@pytest.mark.parametrize("kind", ["nn", "boucwen"])
def test_load_refuses_shape_disagreeing_with_header(kind, tmp_path):
    path = get_model(kind).save(tmp_path / "m.npz")
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    key = "b1" if kind == "nn" else "k0"
    arrays[key] = np.zeros(3)
    np.savez(tmp_path / "bad.npz", **arrays)
    with pytest.raises(ModelError, match=rf"bad\.npz: parameter '{key}' has shape \[3\]"):
        load_model(tmp_path / "bad.npz")


def test_boucwen_refuses_zero_c1_and_zero_c0_plus_c2():
    p = BoucWenBushing.preset().params
    with pytest.raises(ModelError, match="c1 = 0"):
        BoucWenBushing(**{**p, "c1": 0.0})
    with pytest.raises(ModelError, match=r"c0 \+ c2 = 0"):
        BoucWenBushing(**{**p, "c0": 1.0, "c2": -1.0})
