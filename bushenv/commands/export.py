"""``bushenv export``: a bushing model as an FMU (FMI 2.0 / 3.0, co-simulation and model exchange,
compiled C)."""

from __future__ import annotations

import argparse
import sys

from bushenv.export.build import export_fmu
from bushenv.export.description import FMI_VERSIONS
from bushenv.export.model_c import BOUCWEN_SUBSTEPS, EXPORTABLE_BY_COORDS

EXAMPLE = "bushenv export nn --fmi 3.0 --out bushing.fmu"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from bushenv.models import AXES

    parser.add_argument(
        "model",
        metavar="MODEL",
        help=f"{', '.join(EXPORTABLE_BY_COORDS[1])} or a model file (.npz) of one or three axes",
    )
    parser.add_argument("--fmi", default="2.0", choices=FMI_VERSIONS, help="FMI version")
    parser.add_argument("--out", required=True, help="the FMU to write (.fmu)")
    parser.add_argument("--axis", default="axial", choices=AXES, help="shipped model's axis")
    parser.add_argument(
        "--axes",
        type=int,
        default=None,
        choices=sorted(EXPORTABLE_BY_COORDS),
        help="coordinates of a registered MODEL: 3 for its three-axis form "
        f"({', '.join(EXPORTABLE_BY_COORDS[3])}; axial, radial, rotation in, force_axial, "
        "force_radial, moment out); a file's own count otherwise (default: 1 for a name)",
    )
    parser.add_argument(
        "--card",
        default=None,
        help="model card (default: MODEL.card.json beside a model file, if there is one)",
    )
    parser.add_argument(
        "--certificate",
        default=None,
        help="certificate.json of bushenv certify, of this model (default: a NARX model is "
        "certified at export)",
    )
    parser.add_argument(
        "--reference",
        default=None,
        help="registered name or model file the certificate run at export compares the static "
        "force with (default: none; wrong sign is judged against the deflection)",
    )
    parser.add_argument(
        "--allow-failing",
        action="store_true",
        help="export a model that fails its certificate (the FMU carries the failing ranges, "
        "raises in_flagged_range inside them and logs a warning)",
    )
    parser.add_argument(
        "--stroke-mm",
        type=float,
        default=None,
        help="envelope stroke instead of the card's (default: the card's, else 12.5)",
    )
    parser.add_argument(
        "--velocity-m-per-s",
        type=float,
        default=None,
        help="envelope velocity instead of the card's (default: the card's, else 1.257)",
    )
    parser.add_argument(
        "--substeps",
        type=int,
        default=BOUCWEN_SUBSTEPS,
        help="Bouc-Wen: RK4 sub-steps per sample in the C",
    )
    parser.add_argument("--quiet", action="store_true", help="print nothing on stderr")


def run(args: argparse.Namespace) -> int:
    from bushenv.cli import CliError

    for name in ("stroke_mm", "velocity_m_per_s"):
        value = getattr(args, name)
        if value is not None and not value > 0:
            raise CliError(f"--{name.replace('_', '-')} must be positive, got {value}")
    done = export_fmu(
        args.model,
        args.out,
        args.fmi,
        axis=args.axis,
        card=args.card,
        certificate=args.certificate,
        stroke_m=args.stroke_mm * 1e-3 if args.stroke_mm is not None else None,
        velocity_m_per_s=args.velocity_m_per_s,
        substeps=args.substeps,
        coords=args.axes,
        reference=args.reference,
        allow_failing=args.allow_failing,
    )
    print(done.path)
    cert = done.certificate
    if cert is not None and cert.fails:
        print(
            "WARNING: exported with --allow-failing although the model fails its certificate: "
            f"{cert.failing or 'holds'}, flagged ranges {cert.ranges_text()} ({cert.source}); "
            "the FMU's in_flagged_range is true while its input lies in one, and it logs a "
            "warning"
        )
    if not args.quiet:
        print(summary(done), file=sys.stderr)
    return 0


def summary(done) -> str:
    """One line on the FMU written (``build.Exported``): its ports, in and out, and its
    envelope per coordinate (mm or mrad; m/s or rad/s), from the FMU's own variables."""
    from bushenv.export.description import PORTS

    ports = PORTS[done.coords]
    env = done.facts.envelope
    strokes, rates = env.limits(done.coords)
    io = f"{', '.join(p.x for p in ports)} in; {', '.join(p.f for p in ports)} out"
    bounds = ", ".join(
        f"|{p.symbol}| <= {s * 1e3:.4g} {'mrad' if p.x_unit == 'rad' else 'mm'}, "
        f"|d{p.symbol}/dt| <= {r:.4g} {p.v_unit}"
        for p, s, r in zip(ports, strokes, rates, strict=True)
    )
    cert = done.certificate
    return (
        f"FMI {done.fmi_version} FMU (co-simulation and model exchange; {io}) of the "
        f"{done.model!r} model, compiled with {done.compiler}; envelope {bounds} "
        f"({env.source}); certificate: {cert.verdict() if cert is not None else 'none'}"
    )
