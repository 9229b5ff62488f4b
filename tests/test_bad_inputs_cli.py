"""The ``bushenv`` command on bad input: one line on stderr (``bushenv CMD: error: ...``), a
non-zero exit code, never a traceback; ``--help`` of every command exits 0 with an example.

Run in-process through ``bushenv.cli.main`` (fast) except where the real process matters.
The catalogue with the messages is docs/bad-inputs.md.
"""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
import types

import pytest

from bushenv import cli
from bushenv.cli import COMMANDS, main
from bushenv.errors import BadInput, ModelRaised


def run_cli(argv: list[str], capsys) -> tuple[int, str, str]:
    """Exit code, stdout, stderr of ``bushenv argv`` run in this process."""
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own errors and --help
        code = exc.code if isinstance(exc.code, int) else 1
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def assert_one_line_error(err: str, command: str, fragment: str) -> None:
    lines = [line for line in err.splitlines() if line.strip() and not line.startswith("[")]
    assert "Traceback" not in err
    assert len(lines) == 1, err
    assert lines[0].startswith(f"bushenv {command}: error: "), lines[0]
    assert fragment in lines[0], lines[0]


def module_or_skip(command: str) -> None:
    module = COMMANDS[command][0]
    try:
        importlib.import_module(module)
    except ImportError as exc:
        pytest.skip(f"{module} is not in this checkout yet ({exc}): pending")


# ----- help ------------------------------------------------------------------------------------
@pytest.mark.parametrize("command", list(COMMANDS))
def test_every_command_help_exits_0_and_shows_an_example(command, capsys):
    module_or_skip(command)
    code, out, err = run_cli([command, "--help"], capsys)
    assert code == 0, err
    assert "example:" in out
    assert f"bushenv {command}" in out.split("example:")[1]


def test_top_level_help_lists_every_command_without_importing_them():
    code = (
        "import sys; from bushenv.cli import main, COMMANDS\n"
        "try:\n    main(['--help'])\nexcept SystemExit as e:\n    assert e.code == 0\n"
        "loaded = [m for m, _ in COMMANDS.values() if m in sys.modules]\n"
        "print('LOADED', loaded)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    for command in COMMANDS:
        assert command in done.stdout
    assert "LOADED []" in done.stdout


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_every_command_shows_its_help_without_importing_torch(command):
    """Torch costs over a second to import: the options' lists are kept out of its modules."""
    code = (
        "import sys; from bushenv.cli import main\n"
        f"try:\n    main([{command!r}, '--help'])\n"
        "except SystemExit as e:\n    assert e.code == 0\n"
        "print('TORCH', 'torch' in sys.modules)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert "TORCH False" in done.stdout


def test_no_command_prints_help_and_exits_2(capsys):
    code, out, _ = run_cli([], capsys)
    assert code == 2
    assert "COMMAND" in out


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["bogus"], "invalid choice: 'bogus'"),
        (["--bogus"], "unrecognized arguments: --bogus"),
        (["measure", "--out", "x", "--bogus"], "unrecognized arguments: --bogus"),
        (["measure", "--out", "x", "--programme", "sines"], "invalid choice: 'sines'"),
        (["measure", "--out", "x", "--rate", "fast"], "invalid float value: 'fast'"),
        (["measure"], "the following arguments are required: --out"),
        (["campaign", "--out", "x", "--budget", "1e3"], "invalid int value: '1e3'"),
        (["campaign", "--out", "x", "--env", "moon"], "invalid choice: 'moon'"),
        (["measure", "--out", "x", "--mod", "linear"], "unrecognized arguments: --mod"),
    ],
    ids=[
        "unknown-command",
        "unknown-top-option",
        "unknown-option",
        "bad-choice",
        "not-a-number",
        "missing-required",
        "float-for-int",
        "bad-env",
        "no-abbreviations",
    ],
)
def test_argument_errors_exit_2_with_usage_and_one_error_line(argv, fragment, capsys):
    code, _, err = run_cli(argv, capsys)
    assert code == 2
    assert "Traceback" not in err
    assert err.strip().splitlines()[-1].endswith(fragment) or fragment in err.splitlines()[-1]
    assert err.strip().splitlines()[0].startswith("usage: bushenv")


# ----- failures inside a command -----------------------------------------------------------------
@pytest.fixture()
def fake_command(monkeypatch):
    """Install a throw-away command 'fake' whose run raises what the test asks."""
    module = types.ModuleType("bushenv_fake_command")
    module.EXAMPLE = "bushenv fake"
    module.add_arguments = lambda p: None
    module.to_raise = None

    def run(args):
        raise module.to_raise

    module.run = run
    monkeypatch.setitem(sys.modules, module.__name__, module)
    monkeypatch.setitem(COMMANDS, "fake", (module.__name__, "a test command"))
    return module


def test_missing_command_module_is_one_line_not_a_traceback(monkeypatch, capsys):
    monkeypatch.setitem(COMMANDS, "ghost", ("bushenv.no_such_module", "not installed"))
    for argv in (["ghost"], ["ghost", "--help"]):
        code, _, err = run_cli(argv, capsys)
        assert code == 2
        assert_one_line_error(err, "ghost", "not available in this install")
    code, out, _ = run_cli(["--help"], capsys)  # the others still work
    assert code == 0 and "ghost" in out


def test_unexpected_exception_is_one_line_naming_its_type_with_exit_1(fake_command, capsys):
    fake_command.to_raise = RuntimeError("kernel\nexploded")
    code, _, err = run_cli(["fake"], capsys)
    assert code == 1
    assert "Traceback" not in err
    assert err.strip() == (
        "bushenv fake: internal error: RuntimeError: kernel exploded "
        "(a bug: please report it; BUSHENV_DEBUG=1 shows the traceback)"
    )


def test_debug_variable_shows_the_traceback_of_an_unexpected_exception(fake_command, monkeypatch):
    fake_command.to_raise = RuntimeError("kernel exploded")
    monkeypatch.setenv("BUSHENV_DEBUG", "1")
    with pytest.raises(RuntimeError, match="kernel exploded"):
        main(["fake"])


@pytest.mark.parametrize(
    ("exc", "code", "line"),
    [
        (KeyboardInterrupt(), 130, "bushenv fake: interrupted; results written so far are kept"),
        (cli.Terminated(), 143, "bushenv fake: terminated; results written so far are kept"),
        (BadInput("x.csv line 3: bad"), 2, "bushenv fake: error: x.csv line 3: bad"),
        (
            ValueError("operands could not be broadcast"),
            1,
            "bushenv fake: internal error: ValueError: operands could not be broadcast "
            "(a bug: please report it; BUSHENV_DEBUG=1 shows the traceback)",
        ),
        (
            ModelRaised("mine.npz", ValueError("operands could not be broadcast")),
            3,
            "bushenv fake: model error: mine.npz: ValueError: operands could not be broadcast "
            "(the model's own code raised; this is not a divergence verdict)",
        ),
        (
            FileNotFoundError(2, "No such file or directory", "/nope/a.csv"),
            2,
            "bushenv fake: error: [Errno 2] No such file or directory: '/nope/a.csv'",
        ),
        (cli.CliError("--budget must be > 0"), 2, "bushenv fake: error: --budget must be > 0"),
    ],
    ids=[
        "ctrl-c",
        "sigterm",
        "bad-input",
        "plain-value-error",
        "model-error",
        "os-error",
        "cli-error",
    ],  # fmt: skip
)
def test_known_failures_map_to_one_line_and_an_exit_code(fake_command, capsys, exc, code, line):
    fake_command.to_raise = exc
    got, _, err = run_cli(["fake"], capsys)
    assert got == code
    assert err.strip() == line


# ----- measure ---------------------------------------------------------------------------------
def measure(tmp_path, *extra: str) -> list[str]:
    return ["measure", "--programme", "random", "--duration", "1", "--quiet", *extra]


@pytest.mark.parametrize(
    ("extra", "fragment"),
    [
        (["--model", "lstm"], "unknown model 'lstm'; known names:"),
        (["--model", ""], "empty model name"),
        (["--model", "missing.npz"], "missing.npz: no such model file"),
        (["--rate", "0"], "--rate must be a positive number of Hz, got 0.0"),
        (["--rate", "nan"], "--rate must be a positive number of Hz, got nan"),
        (["--rate", "-204.8"], "--rate must be a positive number of Hz"),
        (["--seed", "-1"], "--seed must be >= 0, got -1"),
        (["--duration", "-5"], "duration_s must be a finite number >= 0, got -5.0"),
        (["--duration", "inf"], "duration_s must be a finite number >= 0, got inf"),
        (["--duration", "1e9"], "more than the 1e+07 one signal may hold"),
        (["--n", "-1"], "n_index must be a finite number >= 0, got -1.0"),
        (["--n", "100"], "outside the test machine's limits"),
    ],
    ids=[
        "unknown-model",
        "empty-model",
        "missing-model-file",
        "zero-rate",
        "nan-rate",
        "negative-rate",
        "negative-seed",
        "negative-duration",
        "infinite-duration",
        "absurd-duration",
        "negative-n",
        "beyond-stroke",
    ],
)
def test_measure_bad_arguments_are_one_line_errors(tmp_path, capsys, extra, fragment):
    code, _, err = run_cli([*measure(tmp_path), "--out", str(tmp_path / "out"), *extra], capsys)
    assert code == 2
    assert_one_line_error(err, "measure", fragment)
    assert not (tmp_path / "out").exists()  # nothing written on refusal


def test_measure_refuses_a_png_given_as_model(tmp_path, capsys):
    png = tmp_path / "plot.png"
    png.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR")
    code, _, err = run_cli(
        [*measure(tmp_path), "--model", str(png), "--out", str(tmp_path / "o")], capsys
    )
    assert code == 2
    assert_one_line_error(err, "measure", "plot.png: not a bushenv model file: a PNG image")


def test_measure_refuses_an_out_path_that_is_a_file(tmp_path, capsys):
    target = tmp_path / "records"
    target.write_text("not a folder")
    code, _, err = run_cli([*measure(tmp_path), "--out", str(target)], capsys)
    assert code == 2
    assert_one_line_error(err, "measure", "exists and is not a folder")
    assert target.read_text() == "not a folder"


def test_measure_into_a_folder_under_a_regular_file_is_one_line(tmp_path, capsys):
    parent = tmp_path / "a_file"
    parent.write_text("x")
    code, _, err = run_cli([*measure(tmp_path), "--out", str(parent / "records")], capsys)
    assert code == 2
    assert_one_line_error(err, "measure", "Not a directory")


def test_measure_into_a_read_only_folder_is_one_line(tmp_path, capsys):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        probe = locked / ".probe"
        try:
            probe.touch()
        except PermissionError:
            pass
        else:
            probe.unlink()
            pytest.skip(
                "running as root (or with CAP_DAC_OVERRIDE): chmod does not stop writes; "
                "test_measure_into_a_folder_under_a_regular_file_is_one_line covers the path"
            )
        code, _, err = run_cli([*measure(tmp_path), "--out", str(locked / "out")], capsys)
        assert code == 2
        assert_one_line_error(err, "measure", "Permission denied")
    finally:
        locked.chmod(0o700)


def test_measure_refuses_to_overwrite_records_without_force(tmp_path, capsys):
    argv = [*measure(tmp_path), "--out", str(tmp_path / "r")]
    assert run_cli(argv, capsys)[0] == 0
    written = sorted((tmp_path / "r").iterdir())
    before = [p.read_bytes() for p in written]
    code, _, err = run_cli(argv, capsys)
    assert code == 2
    assert_one_line_error(err, "measure", "already exist")
    assert [p.read_bytes() for p in written] == before


# ----- campaign --------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("extra", "fragment"),
    [
        (["--budget", "0"], "--budget must be a positive number of evaluations, got 0"),
        (["--budget", "-5"], "--budget must be a positive number of evaluations, got -5"),
        (["--models", "lstm"], "unknown model 'lstm'"),
        (["--models", ","], "--models ',' names nothing"),
        (["--axes", "sideways"], "unknown axis 'sideways'"),
        (["--searchers", "foo"], "unknown searcher 'foo'"),
        (["--seeds", "a-b"], "--seeds 'a-b': expected e.g. 0-9 or 1,4,7"),
        (["--seeds", "-3"], "seeds must be >= 0, got -3"),
        (["--seeds", "9-2"], "runs backwards"),
        (["--workers", "0"], "workers must be >= 1, got 0"),
    ],
    ids=[
        "zero-budget",
        "negative-budget",
        "unknown-model",
        "no-model",
        "unknown-axis",
        "unknown-searcher",
        "bad-seeds",
        "negative-seed",
        "backwards-seeds",
        "zero-workers",
    ],
)
def test_campaign_bad_arguments_are_one_line_errors_before_anything_runs(
    tmp_path, capsys, extra, fragment
):
    out = tmp_path / "m"
    argv = ["campaign", "--models", "linear", "--seeds", "0", "--budget", "8", "--out", str(out)]
    code, _, err = run_cli([*argv, *extra], capsys)
    assert code == 2
    assert_one_line_error(err, "campaign", fragment)
    assert not out.exists()


def test_campaign_refuses_an_out_path_that_is_a_file(tmp_path, capsys):
    target = tmp_path / "m"
    target.write_text("keep me")
    argv = ["campaign", "--models", "linear", "--seeds", "0", "--budget", "8", "--out", str(target)]
    code, _, err = run_cli(argv, capsys)
    assert code == 2
    assert_one_line_error(err, "campaign", "exists and is not a folder")
    assert target.read_text() == "keep me"


def test_campaign_without_a_shipped_default_model_stops_before_starting(
    tmp_path, capsys, monkeypatch
):
    import bushenv.models

    # as in a checkout where scripts/train_default_models.py has not run
    monkeypatch.setattr(bushenv.models, "default_model_path", lambda n, a: tmp_path / "none.npz")
    out = tmp_path / "m"
    argv = ["campaign", "--models", "boucwen", "--axes", "radial", "--out", str(out)]
    code, _, err = run_cli(argv, capsys)
    assert code == 2
    assert_one_line_error(err, "campaign", "model 'boucwen' (radial): no default 'boucwen'")
    assert not out.exists()


# ----- diagnose, reproduce, diagnose-validate -----------------------------------------------------
GOOD_CSV = "time,displacement,force\n0.0,0.0,0.0\n0.1,0.001,10.0\n0.2,0.002,20.0\n"


@pytest.mark.parametrize(
    ("train", "fragment"),
    [
        (None, "no such record file"),
        (b"\x89PNG\r\n\x1a\n", "binary data (a PNG image)"),
        (GOOD_CSV.replace("0.2,", "0.05,").encode(), "line 4: time goes backwards"),
        (GOOD_CSV.replace("0.002,", "2.0,").encode(), "looks like millimetres"),
    ],
    ids=["missing", "png", "time-backwards", "millimetres"],
)
def test_diagnose_refuses_a_bad_record_in_one_line(tmp_path, capsys, train, fragment):
    module_or_skip("diagnose")
    train_path = tmp_path / "train.csv"
    if train is not None:
        train_path.write_bytes(train)
    test_path = tmp_path / "test.csv"
    test_path.write_text(GOOD_CSV)
    argv = ["diagnose", str(train_path), str(test_path), "--out", str(tmp_path / "d"), "--quiet"]
    code, _, err = run_cli(argv, capsys)
    assert code == 2
    assert_one_line_error(err, "diagnose", fragment)


def test_diagnose_refuses_an_existing_out_folder(tmp_path, capsys):
    module_or_skip("diagnose")
    (tmp_path / "d").mkdir()
    (tmp_path / "t.csv").write_text(GOOD_CSV)
    argv = ["diagnose", str(tmp_path / "t.csv"), str(tmp_path / "t.csv"), "--out"]
    code, _, err = run_cli([*argv, str(tmp_path / "d"), "--quiet"], capsys)
    assert code == 2
    assert_one_line_error(err, "diagnose", "folder already exists")


def test_reproduce_refuses_an_unknown_axis_and_an_existing_report(tmp_path, capsys):
    module_or_skip("reproduce")
    code, _, err = run_cli(["reproduce", "--out", str(tmp_path / "r"), "--axes", "up"], capsys)
    assert code == 2
    assert_one_line_error(err, "reproduce", "unknown axis 'up'")
    (tmp_path / "r").mkdir()
    (tmp_path / "r" / "report.json").write_text("{}")
    code, _, err = run_cli(["reproduce", "--out", str(tmp_path / "r")], capsys)
    assert code == 2
    assert_one_line_error(err, "reproduce", "report.json exists; pass --force")
    assert (tmp_path / "r" / "report.json").read_text() == "{}"


def test_diagnose_validate_refuses_zero_cases(tmp_path, capsys):
    module_or_skip("diagnose-validate")
    argv = ["diagnose-validate", "--cases", "0", "--out", str(tmp_path / "v")]
    code, _, err = run_cli(argv, capsys)
    assert code == 2
    assert_one_line_error(err, "diagnose-validate", "--cases must be >= 1, got 0")


# ----- real processes ----------------------------------------------------------------------------
def test_installed_command_gives_one_line_and_exit_2_in_a_real_process(tmp_path):
    exe = [sys.executable, "-c", "import sys; from bushenv.cli import main; sys.exit(main())"]
    done = subprocess.run(
        [*exe, "measure", "--model", "lstm", "--out", str(tmp_path / "o")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("bushenv measure: error: unknown model 'lstm'")


def test_python_dash_m_catches_the_same_cli_errors_as_the_installed_command(tmp_path):
    # `python -m bushenv.cli` runs cli.py as __main__; command modules raise bushenv.cli's
    # CliError, which that copy's main must still recognise (it did not: exit 1, "internal").
    out = str(tmp_path / "m")
    done = subprocess.run(
        [sys.executable, "-m", "bushenv.cli", "campaign", "--budget", "0", "--out", out],
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "BUSHENV_DEBUG": ""},
    )
    assert done.returncode == 2
    assert done.stderr.strip() == (
        "bushenv campaign: error: --budget must be a positive number of evaluations, got 0"
    )


@pytest.mark.parametrize("budget", ["0", "-3"])
def test_attack_refuses_a_budget_below_one(tmp_path, capsys, budget):
    module_or_skip("attack")
    argv = ["attack", "--model", "linear", "--budget", budget, "--out", str(tmp_path / "a")]
    code, _, err = run_cli(argv, capsys)
    assert code == 2
    assert_one_line_error(err, "attack", "--budget and --rl-budget must be >= 1")
    assert not (tmp_path / "a").exists()
