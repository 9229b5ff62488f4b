"""The ``bushenv`` command: parses arguments, hands them to a library module, prints.

Each sub-command lives in the module named below, which provides ``add_arguments(parser)`` and
``run(args) -> int`` (or ``cli_run(args)`` where the module's ``run`` is a library function).
Modules are imported only when their command runs, so ``bushenv --help`` is fast and one
broken optional part cannot take the others down.
"""

from __future__ import annotations

import argparse
import importlib
import os
import signal
import sys
import threading

from bushenv.errors import BadInput, ModelRaised

COMMANDS = {
    # name: (module, one-line help)
    "reproduce": ("bushenv.commands.reproduce", "identify every model; the papers' tables beside"),
    "attack": ("bushenv.commands.attack", "adversarial campaign: excitations that break a model"),
    "campaign": ("bushenv.commands.campaign", "campaign matrix: models x axes x searchers x seeds"),
    "replay": ("bushenv.commands.replay", "replay a regression corpus; name every changed verdict"),
    "diagnose": ("bushenv.commands.diagnose", "sim-to-real gap: where, which effect, how far"),
    "diagnose-validate": (
        "bushenv.commands.diagnose_validate",
        "blind validation of the gap diagnosis",
    ),
    "measure": ("bushenv.commands.measure", "run a test programme on a model; write CSV records"),
    "fit": ("bushenv.commands.fit", "identify a model from measured records, with a card"),
    "import-nn": ("bushenv.commands.import_nn", "a torch NARX network to a model file"),
    "card": ("bushenv.commands.card", "show a model card; check its model and records"),
    "certify": ("bushenv.commands.certify", "hold-stability and passivity certificates of a NARX"),
    "zoo": ("bushenv.commands.zoo", "population study: how often NARX models fail, by recipe"),
    "export": ("bushenv.commands.export", "a model as an FMU (FMI 2.0 / 3.0, compiled C)"),
    "vehicle": ("bushenv.commands.vehicle", "standard manoeuvres: bushing kinds in a half car"),
    "vehicle-transfer": (
        "bushenv.commands.vehicle_transfer",
        "error-transfer map: which bushing errors reach the half car",
    ),
}


class CliError(BadInput):
    """A user-facing problem: printed as one line, exit code 2."""


class HelpFormatter(argparse.RawDescriptionHelpFormatter, argparse.ArgumentDefaultsHelpFormatter):
    """Descriptions as written, and every option's default in ``--help`` (once: a help text
    that states its default in words keeps its own)."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        if "(default" in text:
            return text
        return super()._get_help_string(action)


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The parser; only the module of ``only`` (the command being run) is imported.

    Without a command (``bushenv --help``, a typo) no command module is imported, so the
    top-level help is fast and works even when one command's module is missing or broken.
    Raises ``CliError`` when the module of ``only`` cannot be imported.
    """
    parser = argparse.ArgumentParser(
        prog="bushenv",
        description="Stress-test rubber-bushing force models (see README.md).",
        epilog="Run 'bushenv COMMAND --help' for a command's options and an example.",
        allow_abbrev=False,
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (_module, help_text) in COMMANDS.items():
        if name != only:
            sub.add_parser(name, help=help_text, add_help=False)
            continue
        p = sub.add_parser(
            name,
            help=help_text,
            description=help_text,
            formatter_class=HelpFormatter,
            allow_abbrev=False,
        )
        mod = _command_module(name)
        mod.add_arguments(p)
        if getattr(mod, "EXAMPLE", None):
            p.epilog = "example:\n  " + mod.EXAMPLE
    return parser


def _command_module(name: str):
    module = COMMANDS[name][0]
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        # A command whose module is absent from this install (or needs a missing package)
        # must not take the others down, nor print a traceback.
        raise CliError(f"this command is not available in this install ({module}: {exc})") from None


def main(argv: list[str] | None = None) -> int:
    """Run one command; returns the exit code: 0 ok, 1 a bug (or the command's own "failed"
    verdict: ``replay``, ``certify``), 2 bad input, 3 a model raised while it ran, 130/143
    interrupted (``bushenv.errors`` says which error is which).

    Every failure is one line on stderr: ``bushenv COMMAND: error: ...`` for bad input,
    ``bushenv COMMAND: model error: ...`` with the model's own message, and for an unexpected
    exception (a bug) one line naming its type; ``BUSHENV_DEBUG=1`` shows the full traceback.
    """
    argv = list(sys.argv[1:] if argv is None else argv)
    only = argv[0] if argv and argv[0] in COMMANDS else None
    try:
        parser = build_parser(only)
    except CliError as exc:
        print(f"bushenv {only}: error: {exc}", file=sys.stderr)
        return 2
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 2
    mod = _command_module(args.command)
    runner = getattr(mod, "cli_run", None) or mod.run  # cli_run where run() means something else
    previous = _handle_sigterm()
    try:
        return int(runner(args) or 0)
    except KeyboardInterrupt as exc:
        how = "terminated" if isinstance(exc, Terminated) else "interrupted"
        print(f"bushenv {args.command}: {how}; results written so far are kept", file=sys.stderr)
        return 143 if isinstance(exc, Terminated) else 130
    except (BadInput, OSError) as exc:
        # Our loaders raise BadInput subclasses with file/line/value in the message.
        print(f"bushenv {args.command}: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except ModelRaised as exc:
        if os.environ.get("BUSHENV_DEBUG"):
            raise
        print(
            f"bushenv {args.command}: model error: {_one_line(exc)} (the model's own code "
            "raised; this is not a divergence verdict)",
            file=sys.stderr,
        )
        return 3
    except Exception as exc:
        if os.environ.get("BUSHENV_DEBUG"):
            raise
        print(
            f"bushenv {args.command}: internal error: {type(exc).__name__}: {_one_line(exc)} "
            "(a bug: please report it; BUSHENV_DEBUG=1 shows the traceback)",
            file=sys.stderr,
        )
        return 1
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill PID``) arrived: unwind like Ctrl-C so every command's clean-up runs."""


def _raise_terminated(signum, frame) -> None:
    raise Terminated()


def _handle_sigterm():
    """Make SIGTERM unwind like Ctrl-C (main thread only); returns the previous handler."""
    if threading.current_thread() is not threading.main_thread():
        return None
    return signal.signal(signal.SIGTERM, _raise_terminated)


def _one_line(exc: BaseException) -> str:
    text = str(exc) or type(exc).__name__
    if isinstance(exc, OSError) and exc.filename is not None and str(exc.filename) not in text:
        text = f"{exc.filename}: {text}"
    return " ".join(text.split())


if __name__ == "__main__":
    # Run the imported module's main, not this __main__ copy: command modules raise
    # bushenv.cli.CliError, which must be the class main() catches.
    from bushenv.cli import main as _main

    sys.exit(_main())
