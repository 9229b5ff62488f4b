"""Bad input to ``bushenv export`` and to the FMU loader: one line, exit 2, naming the fix."""

import os
import shutil
import zipfile

import pytest

from bushenv.cli import main
from bushenv.models import ModelError, get_model

pytest.importorskip("fmpy")


def _error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    return err


def test_an_unknown_model_kind_is_refused_naming_the_known_ones(tmp_path, capsys):
    assert main(["export", "spring", "--out", str(tmp_path / "a.fmu")]) == 2
    assert "unknown model 'spring'" in _error(capsys)
    assert main(["export", "rubber", "--out", str(tmp_path / "a.fmu")]) == 2
    assert "exportable kinds: linear, nn, hybrid, boucwen" in _error(capsys)
    assert not (tmp_path / "a.fmu").exists()


def test_no_c_compiler_names_the_one_looked_for_and_how_to_install(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("CC", "no-such-cc")
    assert main(["export", "linear", "--out", str(tmp_path / "a.fmu")]) == 2
    err = _error(capsys)
    assert "$CC='no-such-cc'" in err and "apt-get install gcc" in err
    monkeypatch.delenv("CC")
    monkeypatch.setenv("PATH", str(tmp_path))  # neither cc nor gcc
    assert main(["export", "linear", "--out", str(tmp_path / "a.fmu")]) == 2
    assert "'cc' and 'gcc' on PATH" in _error(capsys)


def test_a_read_only_output_folder_is_refused(tmp_path, capsys):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    # root writes into a 0o555 folder anyway; /proc refuses new files to everyone
    target = folder if os.geteuid() != 0 else "/proc"
    try:
        assert main(["export", "linear", "--out", f"{target}/a.fmu"]) == 2
    finally:
        folder.chmod(0o755)
    err = _error(capsys)
    assert "a.fmu" in err and ("not writable" in err or "read-only" in err)


def test_an_output_name_without_fmu_or_in_a_missing_folder_is_refused(tmp_path, capsys):
    assert main(["export", "linear", "--out", str(tmp_path / "a.zip")]) == 2
    assert "must end in .fmu" in _error(capsys)
    assert main(["export", "linear", "--out", str(tmp_path / "no" / "a.fmu")]) == 2
    assert "does not exist" in _error(capsys)


def test_a_damaged_fmu_is_refused_as_a_model(tmp_path, fmu):
    text = tmp_path / "text.fmu"
    text.write_text("not a zip")
    with pytest.raises(ModelError, match="damaged FMU: not a zip archive"):
        get_model(str(text))
    cut = tmp_path / "cut.fmu"
    cut.write_bytes(fmu("linear", "2.0").read_bytes()[:400])
    with pytest.raises(ModelError, match="damaged FMU"):
        get_model(str(cut))
    bad_xml = tmp_path / "bad.fmu"
    with zipfile.ZipFile(fmu("linear", "2.0")) as src, zipfile.ZipFile(bad_xml, "w") as dst:
        for item in src.namelist():
            data = src.read(item)
            dst.writestr(item, data[:100] if item == "modelDescription.xml" else data)
    with pytest.raises(ModelError, match="modelDescription.xml cannot be read"):
        get_model(str(bad_xml))


def test_an_fmu_lacking_co_simulation_or_a_force_output_is_refused_naming_it(tmp_path, fmu):
    def edited(name, old, new):
        out = tmp_path / name
        with zipfile.ZipFile(fmu("nn", "2.0")) as src, zipfile.ZipFile(out, "w") as dst:
            for item in src.namelist():
                data = src.read(item)
                if item == "modelDescription.xml":
                    data = data.decode().replace(old, new).encode()
                dst.writestr(item, data)
        return out

    with zipfile.ZipFile(fmu("nn", "2.0")) as src:
        text = src.read("modelDescription.xml").decode()
    co_simulation = text[text.index("  <CoSimulation") : text.index("</CoSimulation>") + 16]
    with pytest.raises(ModelError, match="lacks co-simulation"):
        get_model(str(edited("me.fmu", co_simulation, "")))
    with pytest.raises(ModelError, match="lacks a Real output 'force'"):
        get_model(str(edited("noout.fmu", 'causality="output"', 'causality="local"')))
    with pytest.raises(ModelError, match="lacks a Real input 'deflection'"):
        get_model(str(edited("noin.fmu", 'causality="input"', 'causality="local"')))


def test_the_cli_refuses_a_damaged_fmu_as_a_model_in_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.fmu"
    shutil.copyfile(__file__, bad)
    assert main(["certify", str(bad), "--out", str(tmp_path / "c")]) == 2
    assert "damaged FMU" in _error(capsys)


def test_an_fmu_without_a_sample_time_needs_dt(tmp_path, fmu):
    out = tmp_path / "nodt.fmu"
    with zipfile.ZipFile(fmu("nn", "3.0")) as src, zipfile.ZipFile(out, "w") as dst:
        for item in src.namelist():
            data = src.read(item)
            if item == "modelDescription.xml":
                text = data.decode()
                start = text.index("  <DefaultExperiment")
                data = (text[:start] + text[text.index("\n", start) + 1 :]).encode()
            dst.writestr(item, data)
    with pytest.raises(ModelError, match="states no sample time"):
        get_model(str(out))
    assert get_model(str(out), dt=1 / 204.8).dt == 1 / 204.8


def test_a_card_that_no_longer_matches_its_model_stops_the_export(tmp_path, capsys):
    from bushenv.identify.card import new_card, write_card

    model = get_model("linear")
    path = model.save(tmp_path / "lin.npz")
    write_card(new_card(model, path, {"kind": "fit", "seed": 0, "wall_time_s": 0.0}), path)
    type(model)(k_n_per_m=1.0, c_ns_per_m=1.0).save(path)  # replaced after the card
    assert main(["export", str(path), "--out", str(tmp_path / "a.fmu")]) == 2
    assert "does not match the card" in _error(capsys)
    assert not (tmp_path / "a.fmu").exists()


def test_export_command_writes_the_fmu_and_names_it(tmp_path, capsys):
    out = tmp_path / "lin.fmu"
    assert main(["export", "linear", "--fmi", "3.0", "--out", str(out), "--stroke-mm", "3"]) == 0
    captured = capsys.readouterr()
    assert captured.out.strip() == str(out)
    assert "deflection in; force out" in captured.err
    assert "envelope |x| <= 3 mm, |dx/dt| <= 1.257 m/s" in captured.err
    assert main(["export", "linear", "--out", str(out), "--stroke-mm", "-1"]) == 2
    assert "--stroke-mm must be positive" in _error(capsys)


def test_the_card_of_another_model_is_refused(tmp_path, capsys):
    from bushenv.identify.card import new_card, write_card

    model = get_model("linear")
    path = model.save(tmp_path / "lin.npz")
    write_card(new_card(model, path, {"kind": "fit", "seed": 0, "wall_time_s": 0.0}), path)
    other = type(model)(k_n_per_m=1.0, c_ns_per_m=1.0).save(tmp_path / "other.npz")
    card = tmp_path / "lin.card.json"
    assert main(["export", str(other), "--card", str(card), "--out", str(tmp_path / "a.fmu")]) == 2
    assert "describes lin.npz, not the model being exported" in _error(capsys)
