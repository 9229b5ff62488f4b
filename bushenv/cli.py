"""The ``bushenv`` command: parses arguments, hands them to a library module, prints.

Each sub-command lives in the module named below, which provides ``add_arguments(parser)`` and
``run(args) -> int`` (or ``cli_run(args)`` where the module's ``run`` is a library function).
Modules are imported only when their command runs, so ``bushenv --help`` is fast and one
broken optional part cannot take the others down.
"""

from __future__ import annotations

import argparse
import importlib
import sys

COMMANDS = {
    # name: (module, one-line help)
    "reproduce": ("bushenv.reproduce", "identify every model and reproduce the papers' tables"),
    "attack": ("bushenv.search.campaign", "adversarial campaign: excitations that break a model"),
    "campaign": ("bushenv.search.matrix", "campaign matrix: models x axes x searchers x seeds"),
    "diagnose": ("bushenv.diagnose.report", "sim-to-real gap: where, which effect, how far"),
    "diagnose-validate": ("bushenv.diagnose.validate", "blind validation of the gap diagnosis"),
    "measure": ("bushenv.machine", "run a test programme on a model and write CSV records"),
}


class CliError(Exception):
    """A user-facing problem: printed as one line, exit code 2."""


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="bushenv",
        description="Stress-test rubber-bushing force models (see README.md).",
        allow_abbrev=False,
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (module, help_text) in COMMANDS.items():
        if only is not None and name != only:
            sub.add_parser(name, help=help_text, add_help=False)
            continue
        p = sub.add_parser(
            name,
            help=help_text,
            description=help_text,
            formatter_class=argparse.RawDescriptionHelpFormatter,
            allow_abbrev=False,
        )
        mod = importlib.import_module(module)
        mod.add_arguments(p)
        if getattr(mod, "EXAMPLE", None):
            p.epilog = "example:\n  " + mod.EXAMPLE
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    only = argv[0] if argv and argv[0] in COMMANDS else None
    parser = build_parser(only)
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 2
    mod = importlib.import_module(COMMANDS[args.command][0])
    runner = getattr(mod, "cli_run", None) or mod.run  # cli_run where run() means something else
    try:
        return int(runner(args) or 0)
    except KeyboardInterrupt:
        print("bushenv: interrupted; results written so far are kept", file=sys.stderr)
        return 130
    except CliError as exc:
        print(f"bushenv {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except (ValueError, OSError) as exc:
        # Our loaders raise ValueError subclasses with file/line/value in the message.
        print(f"bushenv {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
