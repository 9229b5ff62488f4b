"""Importing torch NARX networks: the imported model runs as the torch net does, in free run."""

import pickle

import numpy as np
import pytest
import torch
from standin import DT, standin_drive

from bushenv.cli import main
from bushenv.identify.card import load_card
from bushenv.identify.torch_import import (
    NarxScaling,
    TorchImportError,
    import_torch_narx,
    input_permutation,
)
from bushenv.models import load_model

SCALING = NarxScaling(x_scale_m=0.0025, f_scale_n=900.0, x_offset_m=1e-4, f_offset_n=-30.0)


def make_net(n_in: int, hidden: tuple[int, ...], seed: int) -> torch.nn.Sequential:
    torch.manual_seed(seed)
    layers: list[torch.nn.Module] = []
    width = n_in
    for h in hidden:
        layers += [torch.nn.Linear(width, h), torch.nn.Tanh()]
        width = h
    layers.append(torch.nn.Linear(width, 1))
    return torch.nn.Sequential(*layers).double()


def user_inputs(xs_hist, ys_hist, order: str, blocks: str) -> list[float]:
    """The input vector a user's net takes: xs_hist = [x_t, x_t-1, ...], ys_hist = [y_t-1, ...]
    (newest first), rearranged to the user's convention."""
    xb, yb = list(xs_hist), list(ys_hist)
    if order == "oldest-first":
        xb, yb = xb[::-1], yb[::-1]
    return xb + yb if blocks == "x-then-f" else yb + xb


def torch_reference_free_run(net, x, nx, nf, scaling, order, blocks, k=0.0, c=0.0):
    """The torch net fed its own outputs step by step from rest: the user's model, written
    independently of bushenv's kernel."""
    xs = (x - scaling.x_offset_m) / scaling.x_scale_m
    x_rest = (0.0 - scaling.x_offset_m) / scaling.x_scale_m
    y_rest = (0.0 - scaling.f_offset_n) / scaling.f_scale_n
    x_past = [x_rest] * nx
    y_past = [y_rest] * nf
    v = np.gradient(x, DT)
    out = np.empty_like(x)
    with torch.no_grad():
        for t in range(len(x)):
            u = user_inputs([xs[t], *x_past], y_past, order, blocks)
            y = float(net(torch.tensor(u, dtype=torch.float64))[0])
            out[t] = k * x[t] + c * v[t] + scaling.f_offset_n + scaling.f_scale_n * y
            x_past = [xs[t], *x_past[:-1]]
            y_past = [y, *y_past[:-1]]
    return out


@pytest.mark.parametrize(
    "lags,hidden,order,blocks",
    [
        ((5, 5), (9,), "newest-first", "x-then-f"),
        ((3, 7), (10, 9), "oldest-first", "x-then-f"),
        ((6, 2), (4,), "newest-first", "f-then-x"),
        ((2, 4), (5, 3), "oldest-first", "f-then-x"),
    ],
)
def test_imported_network_free_runs_as_the_torch_network(lags, hidden, order, blocks):
    nx, nf = lags
    net = make_net(1 + nx + nf, hidden, seed=nx + 10 * nf)
    x = standin_drive(3.0, seed=5)
    ref = torch_reference_free_run(net, x, nx, nf, SCALING, order, blocks)
    for source in (net, net.state_dict()):
        model = import_torch_narx(source, lags, SCALING, input_order=order, block_order=blocks)
        assert model.hidden == hidden
        f = model.simulate(x)
        assert np.max(np.abs(f - ref)) <= 1e-9 * np.max(np.abs(ref))


def test_imported_hybrid_adds_its_backbone_and_saves_to_the_same_file_format(tmp_path):
    net = make_net(11, (9,), seed=1)
    k, c = 3.1e5, 1.7e3
    model = import_torch_narx(
        net.state_dict(), (5, 5), SCALING, model="hybrid", k_n_per_m=k, c_ns_per_m=c
    )
    x = standin_drive(2.0, seed=6)
    ref = torch_reference_free_run(net, x, 5, 5, SCALING, "newest-first", "x-then-f", k, c)
    path = model.save(tmp_path / "h.npz")
    loaded = load_model(path)
    assert loaded.name == "hybrid" and loaded.k_n_per_m == k
    f = loaded.simulate(x)
    assert np.max(np.abs(f - ref)) <= 1e-9 * np.max(np.abs(ref))


def test_the_input_permutation_maps_each_user_position_to_bushenvs():
    # bushenv: [x_t, x_t-1, x_t-2, y_t-1, y_t-2]; user oldest-first, forces first:
    # [y_t-2, y_t-1, x_t-2, x_t-1, x_t]
    perm = input_permutation(2, 2, "oldest-first", "f-then-x")
    assert perm.tolist() == [4, 3, 2, 1, 0]
    assert input_permutation(2, 2, "newest-first", "x-then-f").tolist() == [0, 1, 2, 3, 4]


def test_float32_state_dict_is_imported_exactly_in_float64():
    net = make_net(11, (9,), seed=2).float()
    model = import_torch_narx(net.state_dict(), (5, 5), SCALING)
    assert np.array_equal(model.w1, net[0].weight.detach().double().numpy())


@pytest.mark.parametrize(
    "mutate,message",
    [
        (
            lambda sd: sd.update({"0.weight": torch.zeros(9, 12)}),
            r"'0.weight' has shape \[9, 12\], expected \[H, 11\]",
        ),
        (
            lambda sd: sd.update({"2.weight": torch.zeros(1, 8)}),
            r"'2.weight' has shape \[1, 8\], expected \[1, 9\]",
        ),
        (
            lambda sd: sd.update({"2.weight": torch.zeros(2, 9)}),
            r"'2.weight' has shape \[2, 9\], expected \[1, 9\]",
        ),
        (lambda sd: sd.update({"0.bias": torch.zeros(8)}), r"bias of '0.weight' has shape \[8\]"),
        (
            lambda sd: sd.update({"norm.running_mean": torch.zeros(9)}),
            "unexpected tensor 'norm.running_mean'",
        ),
        (lambda sd: sd.update({"0.weight": torch.zeros(9, 11, 1)}), "expected a 2-D"),
    ],
)
def test_wrong_state_dicts_are_refused_naming_the_tensor_and_the_shape(mutate, message):
    sd = dict(make_net(11, (9,), seed=3).state_dict())
    mutate(sd)
    with pytest.raises(TorchImportError, match=message):
        import_torch_narx(sd, (5, 5), SCALING)


def test_sequential_with_another_activation_or_layer_count_is_refused():
    relu = torch.nn.Sequential(torch.nn.Linear(11, 9), torch.nn.ReLU(), torch.nn.Linear(9, 1))
    with pytest.raises(TorchImportError, match="module 1 is ReLU, expected Tanh"):
        import_torch_narx(relu, (5, 5), SCALING)
    deep = make_net(11, (4, 4, 4), seed=0)
    with pytest.raises(TorchImportError, match="4 Linear layers, expected 2 or 3"):
        import_torch_narx(deep, (5, 5), SCALING)


class _Boom:
    def __reduce__(self):
        import os

        return (os.system, ("touch BOOM_RAN",))


@pytest.mark.filterwarnings("ignore:Detected pickle protocol")
def test_loading_a_torch_file_never_runs_code(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    bad = tmp_path / "evil.pt"
    with open(bad, "wb") as fh:
        pickle.dump({"0.weight": _Boom()}, fh)
    torch.save({"model": _Boom()}, tmp_path / "evil2.pt")
    for path in (bad, tmp_path / "evil2.pt"):
        with pytest.raises(TorchImportError, match="refused by torch.load|not a torch file"):
            import_torch_narx(path, (5, 5), SCALING)
    assert not (tmp_path / "BOOM_RAN").exists()


def test_import_nn_command_writes_the_model_and_a_card(tmp_path, capsys):
    net = make_net(11, (9,), seed=4)
    torch.save(net, tmp_path / "seq.pt")
    out = tmp_path / "nn.npz"
    args = ["import-nn", str(tmp_path / "seq.pt"), "--lags", "5,5", "--out", str(out)]
    scale = ["--x-range-m=-0.0025,0.0025", "--f-scale-n", "900", "--f-offset-n", "-30"]
    assert main(args + scale) == 0
    model = load_model(out)
    x = standin_drive(2.0, seed=7)
    sc = NarxScaling(x_scale_m=0.0025, f_scale_n=900.0, f_offset_n=-30.0)
    ref = torch_reference_free_run(net, x, 5, 5, sc, "newest-first", "x-then-f")
    assert np.max(np.abs(model.simulate(x) - ref)) <= 1e-9 * np.max(np.abs(ref))
    card = load_card(out)
    assert card.data["source"]["kind"] == "torch-import"
    assert card.data["source"]["options"]["x_scale_m"] == 0.0025
    assert "nn.npz" in capsys.readouterr().out


def test_import_nn_command_refuses_a_wrong_shape_in_one_line_and_writes_nothing(tmp_path, capsys):
    torch.save(make_net(11, (9,), seed=4).state_dict(), tmp_path / "sd.pt")
    out = tmp_path / "nn.npz"
    args = ["import-nn", str(tmp_path / "sd.pt"), "--lags", "4,5", "--out", str(out)]
    assert main(args + ["--x-scale-m", "0.002", "--f-scale-n", "900"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "'0.weight' has shape [9, 11], expected [H, 10]" in err
    assert not out.exists()
    assert main(args[:-3] + ["5,5", "--out", str(out), "--f-scale-n", "900"]) == 2
    assert "--x-scale-m" in capsys.readouterr().err
    assert not out.exists()


def test_a_hybrid_needs_its_backbone_and_a_pure_nn_takes_none():
    sd = make_net(11, (9,), seed=5).state_dict()
    with pytest.raises(TorchImportError, match="a hybrid needs its backbone"):
        import_torch_narx(sd, (5, 5), SCALING, model="hybrid", k_n_per_m=1e5)
    with pytest.raises(TorchImportError, match="a pure nn takes neither"):
        import_torch_narx(sd, (5, 5), SCALING, model="nn", k_n_per_m=1e5, c_ns_per_m=1e3)
