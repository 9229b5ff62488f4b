"""An FMU carries its certificate: a NARX model that fails it is refused
unless told, and its FMU flags the failing ranges, as ranges and as an output, and logs them."""

import importlib.util
import json
import zipfile
from pathlib import Path

import numpy as np
import pytest

from bushenv.certify import CertifyOptions, certify
from bushenv.cli import main
from bushenv.export import FailingCertificate, export_fmu
from bushenv.models import PAPER_DT, ModelError

from .fmu_masters import opened

VERSIONS = ("2.0", "3.0")
RING_M = -1.25e-3  # where the test hybrid's hold fixed point is a flip of radius 1.004


def _certify_conftest():
    """tests/certify/conftest.py, loaded by path (its builders, not its fixtures)."""
    path = Path(__file__).resolve().parents[1] / "certify" / "conftest.py"
    spec = importlib.util.spec_from_file_location("certify_builders", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


ringing_hybrid = _certify_conftest().ringing_hybrid


@pytest.fixture(scope="module")
def ring(tmp_path_factory):
    """The ringing hybrid's file and its FMUs exported with --allow-failing."""
    folder = tmp_path_factory.mktemp("ring")
    path = ringing_hybrid().save(folder / "ring.npz")
    made = {v: export_fmu(path, folder / f"ring-{v}.fmu", v, allow_failing=True) for v in VERSIONS}
    return path, made


def _failing_ranges_by_hand(doc):
    """The ranges the FMU must flag, from the certificate's holds: every hold that does not
    settle on a stable fixed point or has the wrong sign stands for the grid cell about it
    (half-way to its neighbours; the grid is uniform), adjacent cells merged."""
    x = np.array([h["x_m"] for h in doc["holds"]])
    bad = np.array(
        [
            h["reached"] is None
            or not h["fixed_points"][h["reached"]]["stable"]
            or h["departs"]
            or h["wrong_sign"]
            for h in doc["holds"]
        ]
    )
    half = 0.5 * (x[1] - x[0])
    out, k = [], 0
    while k < x.size:
        if bad[k]:
            j = k
            while j + 1 < x.size and bad[j + 1]:
                j += 1
            out.append([x[k] - half, x[j] + half])
            k = j + 1
        else:
            k += 1
    return out


def _flagged_fact(fmu_path):
    with zipfile.ZipFile(fmu_path) as zf:
        xml = zf.read("modelDescription.xml").decode()
        doc = json.loads(zf.read("documentation/certificate.json"))
    from fmpy import read_model_description

    md = read_model_description(str(fmu_path))
    start = {v.name: v.start for v in md.modelVariables}
    return json.loads(start["card.certificate_flagged"]), xml, doc


def _drive(fmu_path, x, log=None):
    """Set-then-read at the model's samples: (force, in_flagged_range, outside_envelope)."""
    with opened(fmu_path, log) as (s, vr, three):
        setf = s.setFloat64 if three else s.setReal
        getf = s.getFloat64 if three else s.getReal
        force, flag, outside = np.empty(len(x)), np.empty(len(x), bool), np.empty(len(x), bool)
        for k, xk in enumerate(x):
            setf([vr["deflection"]], [float(xk)])
            force[k] = getf([vr["force"]])[0]
            flag[k], outside[k] = s.getBoolean([vr["in_flagged_range"], vr["outside_envelope"]])
            s.doStep(currentCommunicationPoint=k * PAPER_DT, communicationStepSize=PAPER_DT)
    return force, flag, outside


def _hold_profile():
    """Rest, a 3 mm 10 Hz sine, then holds: inside the flagged range (-1.25 mm), outside it
    (+2 mm, -0.5 mm), inside again (-1.0 mm), each 1 s, joined by 0.1 s ramps."""
    dt = PAPER_DT
    t = np.arange(int(round(0.5 / dt))) * dt
    parts = [np.zeros(20), 3e-3 * np.sin(2 * np.pi * 10.0 * t)]
    for target in (RING_M, 2e-3, -0.5e-3, -1.0e-3):
        parts.append(np.linspace(parts[-1][-1], target, int(round(0.1 / dt))))
        parts.append(np.full(int(round(1.0 / dt)), target))
    return np.concatenate(parts)


def test_a_ringing_hybrid_is_refused_naming_its_ranges_and_the_override(tmp_path, capsys):
    path = ringing_hybrid().save(tmp_path / "ring.npz")
    out = tmp_path / "ring.fmu"
    with pytest.raises(FailingCertificate) as refused:
        export_fmu(path, out)
    text = str(refused.value)
    assert "fails its certificate" in text and "oscillating holds" in text
    assert "-1.8125..-0.6875 mm (oscillates, unstable)" in text
    assert "--allow-failing" in text and not out.exists()
    assert main(["export", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "spectral radius up to 1.004" in err and "--allow-failing" in err
    assert "\n" not in err.strip()  # one line, as every refusal


@pytest.mark.parametrize("version", VERSIONS)
def test_the_fmus_ranges_are_the_certificates_failing_holds(ring, version):
    path, made = ring
    flagged, xml, carried_doc = _flagged_fact(made[version].path)
    doc = certify(ringing_hybrid(), None, CertifyOptions()).document  # as bushenv certify
    want = _failing_ranges_by_hand(doc)
    assert len(want) == 1 and want[0][0] < RING_M < want[0][1]
    assert np.allclose([[lo[0], hi[0]] for lo, hi in flagged], want, rtol=0, atol=1e-15)
    assert carried_doc["summary"] == json.loads(json.dumps(doc["summary"]))
    assert "holds FAILS (7 oscillating holds" in xml and 'name="in_flagged_range"' in xml


@pytest.mark.parametrize("version", VERSIONS)
def test_the_flag_is_raised_while_held_inside_a_flagged_range_and_not_outside(ring, version):
    path, made = ring
    (box,) = made[version].facts.envelope.flagged
    lo, hi = box.lo[0], box.hi[0]
    x = _hold_profile()
    _, flag, outside = _drive(made[version].path, x)
    inside = (x >= lo) & (x <= hi)
    assert np.array_equal(flag, inside)  # sample by sample, the input's membership
    assert np.all(outside[inside])  # the flagged ranges are outside the envelope, as before
    n = int(round(1.0 / PAPER_DT))
    for at, want in ((RING_M, True), (2e-3, False), (-0.5e-3, False), (-1.0e-3, True)):
        k = int(np.argmax(x == at))
        assert np.all(flag[k : k + n] == want), at  # the whole hold


def test_the_fmu_logs_the_failing_certificate_at_init_and_each_entry(ring):
    _, made = ring
    messages = []
    x = _hold_profile()
    _drive(made["3.0"].path, x, log=lambda *a: messages.append(a[3].decode()))
    init = [m for m in messages if m.startswith("this model fails its certificate")]
    entries = [m for m in messages if "enters a range where the model fails" in m]
    assert len(init) == 1 and "--allow-failing" in init[0] and "7 oscillating holds" in init[0]
    (box,) = made["3.0"].facts.envelope.flagged
    inside = (x >= box.lo[0]) & (x <= box.hi[0])
    assert len(entries) == np.count_nonzero(inside[1:] & ~inside[:-1]) + inside[0]  # each entry
    assert len(entries) > 2  # the sine's passes, the holds at -1.25 mm and -1.0 mm
    where = "(oscillates, unstable): x = "
    assert all(where in m and "in [-0.0018125, -0.0006875]" in m for m in entries)
    assert not [m for m in messages if "leaves the bushing's validity envelope" in m]


@pytest.mark.parametrize("version", VERSIONS)
def test_model_exchange_raises_the_flag_in_the_ranges_too(ring, version):
    from fmpy import simulate_fmu

    _, made = ring
    env = made[version].facts.envelope.flagged[0]
    x = _hold_profile()
    t = np.arange(x.size) * PAPER_DT
    sig = np.array(list(zip(t, x, strict=True)), dtype=[("time", float), ("deflection", float)])
    res = simulate_fmu(str(made[version].path), stop_time=t[-1], output_interval=PAPER_DT,
                       input=sig, output=["in_flagged_range"], fmi_type="ModelExchange",
                       record_events=False)  # fmt: skip
    k = np.round(res["time"] / PAPER_DT).astype(int)
    held_in = (x[k] >= env.lo[0]) & (x[k] <= env.hi[0])
    steady = np.r_[False, held_in[1:] == held_in[:-1]]  # away from the crossings
    assert np.array_equal(res["in_flagged_range"][steady], held_in[steady])
    assert held_in.any() and (~held_in).any()


def test_the_shipped_hybrid_exports_without_a_warning(tmp_path, capsys):
    out = tmp_path / "hybrid.fmu"
    assert main(["export", "hybrid", "--fmi", "3.0", "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert captured.out.strip() == str(out)  # the path only, no warning
    assert "holds passes" in captured.err and "WARNING" not in captured.err
    flagged, xml, _ = _flagged_fact(out)
    assert flagged == []
    messages = []
    x = 3e-3 * np.sin(2 * np.pi * 10.0 * np.arange(200) * PAPER_DT)
    _, flag, _ = _drive(out, x, log=lambda *a: messages.append(a[3].decode()))
    assert not flag.any() and messages == []


def test_allow_failing_warns_on_stdout(tmp_path, capsys):
    path = ringing_hybrid().save(tmp_path / "ring.npz")
    out = tmp_path / "ring.fmu"
    assert main(["export", str(path), "--allow-failing", "--out", str(out), "--quiet"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0] == str(out)
    assert lines[1].startswith("WARNING: exported with --allow-failing although the model fails")
    assert "-1.8125..-0.6875 mm (oscillates, unstable)" in lines[1]


def test_a_given_certificate_of_the_model_is_carried_and_one_of_another_is_refused(
    tmp_path, capsys
):
    path = ringing_hybrid().save(tmp_path / "ring.npz")
    argv = ["certify", str(path), "--stroke-mm", "12.5", "--out", str(tmp_path / "c"), "--quiet"]
    assert main(argv) == 1
    cert = tmp_path / "c" / "certificate.json"
    capsys.readouterr()
    with pytest.raises(FailingCertificate, match="certificate.json, given"):
        export_fmu(path, tmp_path / "a.fmu", certificate=cert)
    done = export_fmu(path, tmp_path / "a.fmu", certificate=cert, allow_failing=True)
    ran = export_fmu(path, tmp_path / "b.fmu", allow_failing=True)
    assert done.facts.envelope.flagged == ran.facts.envelope.flagged
    with zipfile.ZipFile(done.path) as zf:
        assert zf.read("documentation/certificate.json") == cert.read_bytes()
    # another network of the same shape and the same backbone: told apart by its fixed points
    other = ringing_hybrid(g=1.002).save(tmp_path / "other.npz")
    with pytest.raises(ModelError, match=r"another model: its fixed points at -12.5 mm"):
        export_fmu(other, tmp_path / "o.fmu", certificate=cert, allow_failing=True)
    # another kind: told apart by its recorded parameters, naming the one that differs
    with pytest.raises(ModelError, match=r"another model \(name 'hybrid', the model exported "):
        export_fmu("nn", tmp_path / "n.fmu", certificate=cert)
    with pytest.raises(ModelError, match="a 'linear' model has no certificate"):
        export_fmu("linear", tmp_path / "l.fmu", certificate=cert)
    with pytest.raises(ModelError, match="a given certificate was made against its own"):
        export_fmu(path, tmp_path / "r.fmu", certificate=cert, reference="rubber")


@pytest.mark.parametrize("kind", ("linear", "boucwen"))
def test_kinds_without_a_recurrence_say_they_have_no_certificate(tmp_path, capsys, kind):
    out = tmp_path / f"{kind}.fmu"
    assert main(["export", kind, "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert f"certificate: none: a '{kind}' model has no recurrence to certify" in err
    with zipfile.ZipFile(out) as zf:
        assert "documentation/certificate.json" not in zf.namelist()


def _three_axis_network(pushing: bool):
    """A small three-axis network over (axial, radial, rotation). ``pushing``: each output a
    tanh of its own coordinate (the force has the sign of the deflection: passes); else random
    small weights, whose static force pulls outward at most holds (wrong sign: fails)."""
    from bushenv.models.planar_narx import N_IN, PlanarNarx

    rng = np.random.default_rng(0)
    w1, w_out = rng.normal(0, 0.05, (9, N_IN)), rng.normal(0, 0.3, (3, 9))
    if pushing:
        w1, w_out = np.zeros((9, N_IN)), np.zeros((3, 9))
        w1[:3, :3] = w_out[:, :3] = np.eye(3)
    return PlanarNarx(
        q_offset=np.zeros(3), q_scale=np.array([2e-3, 2e-3, 0.05]), f_offset=np.zeros(3),
        f_scale=np.array([500.0, 2000.0, 150.0]), w1=w1, b1=np.zeros(9), w_out=w_out,
        b_out=np.zeros(3),
    )  # fmt: skip


def _drive_q(fmu_path, q):
    """Set-then-read of held deflection vectors q (T, 3): in_flagged_range per sample."""
    with opened(fmu_path) as (s, vr, three):
        setf = s.setFloat64 if three else s.setReal
        names = ("deflection_axial", "deflection_radial", "rotation")
        flag = np.empty(len(q), bool)
        for k, qk in enumerate(q):
            setf([vr[n] for n in names], [float(a) for a in qk])
            flag[k] = s.getBoolean([vr["in_flagged_range"]])[0]
            s.doStep(currentCommunicationPoint=k * PAPER_DT, communicationStepSize=PAPER_DT)
    return flag


@pytest.mark.parametrize("version", VERSIONS)
def test_a_three_axis_network_that_fails_is_refused_and_flags_its_boxes(tmp_path, version):
    from bushenv.search.limits import rig3_limits

    THREE_AXIS_STROKES = tuple(rig3_limits()[0])  # no card, no reference: the machine's span
    model = _three_axis_network(pushing=False)
    with pytest.raises(FailingCertificate, match="wrong-sign holds") as refused:
        export_fmu(model, tmp_path / "n3.fmu", version)
    assert "--allow-failing" in str(refused.value)
    done = export_fmu(model, tmp_path / "n3.fmu", version, allow_failing=True)
    doc = certify(model, None, CertifyOptions(span=THREE_AXIS_STROKES)).document
    # by hand: each failing hold vector, +- half the grid spacing per coordinate (the flagged
    # boxes are these, touching ones merged: the same deflections)
    half = np.array(THREE_AXIS_STROKES) / 6
    failing = [h for h in doc["holds"] if h["wrong_sign"] or len(h["fixed_points"]) != 1]
    boxes = [(np.array(h["q"]) - half, np.array(h["q"]) + half) for h in failing]
    flagged, _, _ = _flagged_fact(done.path)
    assert len(failing) == doc["summary"]["wrong_sign_holds"] > 0
    assert 0 < len(flagged) <= len(boxes)
    rng = np.random.default_rng(1)
    q = rng.uniform(-1, 1, (60, 3)) * np.array(THREE_AXIS_STROKES)
    q = np.repeat(q, 2, axis=0)  # each held two samples (the rate limit is not the point)
    want = np.array([any(np.all((p >= lo) & (p <= hi)) for lo, hi in boxes) for p in q])
    assert want.any() and (~want).any()
    assert np.array_equal(_drive_q(done.path, q), want)


def test_a_three_axis_network_that_passes_exports_without_a_flag(tmp_path, capsys):
    path = _three_axis_network(pushing=True).save(tmp_path / "push3.npz")
    out = tmp_path / "push3.fmu"
    assert main(["export", str(path), "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert captured.out.strip() == str(out) and "holds passes" in captured.err
    assert "7^3 hold vectors" in captured.err
    flagged, _, _ = _flagged_fact(out)
    assert flagged == []


def test_a_three_axis_certificate_given_is_carried_and_one_of_another_network_refused(
    tmp_path, capsys
):
    path = _three_axis_network(pushing=False).save(tmp_path / "n3.npz")
    argv = ["certify", str(path), "--stroke-mm", "12.5", "--rotation-mrad", "150", "--holds",
            "343", "--out", str(tmp_path / "c"), "--quiet"]  # fmt: skip
    assert main(argv) == 1
    cert = tmp_path / "c" / "certificate.json"
    given = export_fmu(path, tmp_path / "a.fmu", certificate=cert, allow_failing=True)
    ran = export_fmu(path, tmp_path / "b.fmu", allow_failing=True)
    assert given.facts.envelope.flagged == ran.facts.envelope.flagged
    other = _three_axis_network(pushing=True).save(tmp_path / "push3.npz")
    with pytest.raises(ModelError, match="another model: its fixed points at"):
        export_fmu(other, tmp_path / "o.fmu", certificate=cert)


def test_a_reference_given_is_what_the_certificate_run_at_export_compares_with(tmp_path):
    done = export_fmu("hybrid", tmp_path / "h.fmu", reference="rubber")
    assert "reference rubber" in done.certificate.source and not done.certificate.fails
    with zipfile.ZipFile(done.path) as zf:
        doc = json.loads(zf.read("documentation/certificate.json"))
    assert doc["settings"]["wrong_sign_against"] == "the reference's static force"
    assert all(h["reference_static_force_n"] is not None for h in doc["holds"])
