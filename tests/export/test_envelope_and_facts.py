"""The validity envelope and the model card travel inside the FMU."""

import json
import zipfile

import numpy as np
import pytest

from bushenv import excitation as ex
from bushenv.export import export_fmu
from bushenv.identify.card import new_card, record_entry, write_card
from bushenv.models import PAPER_DT, get_model
from bushenv.records import Record

pytest.importorskip("fmpy")


@pytest.fixture(scope="module")
def carded(tmp_path_factory):
    """A linear model file with a card (one training record of 2 mm, one held out); its FMI
    3.0 FMU (a linear model has no certificate: tests/export/test_certificate_in_fmu.py)."""
    folder = tmp_path_factory.mktemp("carded")
    model = get_model("linear")
    path = model.save(folder / "lin.npz")
    x = ex.sine(2.0, 2e-3, 2.0, PAPER_DT)
    # a name with quotes, markup and non-ASCII: escaped in the XML and in the C
    train = Record.from_arrays(x, model.simulate(x), PAPER_DT, name='train "1" & <a> \u00fc')
    held = Record.from_arrays(0.5 * x, model.simulate(0.5 * x), PAPER_DT, name="held")
    card = new_card(model, path, {"kind": "fit", "seed": 0, "wall_time_s": 0.0})
    card["records"] = [record_entry(train, "train", model), record_entry(held, "held-out", model)]
    write_card(card, path)
    done = export_fmu(path, folder / "lin.fmu", "3.0")
    return done, card


def test_card_facts_are_in_the_model_description(carded):
    from fmpy.validation import validate_fmu

    done, card = carded
    assert validate_fmu(str(done.path)) == []
    with zipfile.ZipFile(done.path) as zf:
        xml = zf.read("modelDescription.xml").decode()
        assert (
            json.loads(zf.read("documentation/card.json"))["model_sha256"] == card["model_sha256"]
        )
    assert card["model_sha256"] in xml
    for r in card["records"]:
        assert r["data_sha256"] in xml
    assert 'name="card.record_2"' in xml and "held-out held: sha256=" in xml and "rms_ratio=" in xml
    from .fmu_masters import opened

    with opened(done.path) as (s, vr, _):
        got = s.getString([vr["card.record_1"]])[0]
    assert got.startswith(
        'train train "1" & <a> \u00fc: sha256=' + card["records"][0]["data_sha256"]
    )
    assert "no recurrence to certify" in xml


def test_envelope_is_the_training_records_range(carded):
    done, card = carded
    env = done.facts.envelope
    train = card["records"][0]
    assert env.stroke_m == train["max_abs_displacement_m"]
    assert env.velocity_m_per_s == train["max_abs_velocity_m_per_s"]
    assert env.flagged == ()


def test_leaving_the_envelope_sets_the_flag_counts_the_time_and_logs(carded):
    """A ramp to 3.2 mm and back: beyond the 2 mm stroke."""
    from .fmu_masters import set_then_read

    done, _ = carded
    dt = PAPER_DT
    x = np.concatenate([np.linspace(0, 3.2e-3, 200), np.linspace(3.2e-3, 0, 200)])
    t = np.arange(len(x)) * dt
    messages = []
    set_then_read(done.path, t, x, np.gradient(x, dt), log=lambda *a: messages.append(a[3]))
    outside = np.abs(x) > done.facts.envelope.stroke_m
    from fmpy import simulate_fmu

    sig = np.array(
        list(zip(t, x, np.gradient(x, dt), strict=True)),
        dtype=[("time", float), ("deflection", float), ("velocity", float)],
    )
    res = simulate_fmu(
        str(done.path),
        stop_time=t[-1],
        output_interval=dt,
        input=sig,
        output=["outside_envelope", "time_outside_envelope_s"],
    )
    # one step late (FMPy reads before it sets the next input): sample k shows at t_(k+1)
    assert np.array_equal(res["outside_envelope"][1:], outside[:-1])
    assert res["time_outside_envelope_s"][-1] == pytest.approx(outside[:-1].sum() * dt)
    entries = [m for m in messages if b"leaves the bushing's validity envelope" in m]
    assert len(entries) == 1 and b"beyond the fitted stroke" in entries[0]


def test_a_model_without_a_card_gets_the_test_machines_envelope(fmu):
    with zipfile.ZipFile(fmu("nn", "2.0")) as zf:
        xml = zf.read("modelDescription.xml").decode()
        names = zf.namelist()
    assert "no MODEL.card.json beside the model file" in xml
    assert 'name="envelope_stroke_m"' in xml and 'start="0.0125"' in xml
    assert "binaries/linux64/bushing.so" in names
    assert {"sources/fmi2.c", "sources/model.h", "sources/core.h"} <= set(names)
