"""Export a bushing model as an FMU: generate the C, compile it, zip it with its description.

``export_fmu(spec, out, fmi_version)`` resolves the model (``get_model``), writes ``model.h``
(``model_c``) with the generated constants (``description.fmu_header``), compiles ``fmi2.c`` or
``fmi3.c`` with the system C compiler into ``binaries/<platform>/bushing.so``, and writes the
archive atomically: modelDescription.xml, the binary, every source under ``sources/`` (with
buildDescription.xml for FMI 3), and the card and certificate under ``documentation/``. A NARX
model's certificate is run (or read, ``certificate``) first: a model that fails it is refused
unless ``allow_failing``, and its failing ranges go into the FMU (``export.certificate``).
"""

from __future__ import annotations

import hashlib
import os
import platform
import shutil
import subprocess
import tempfile
import uuid
import zipfile
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from bushenv.errors import BadInput
from bushenv.export.certificate import carried_certificate
from bushenv.export.description import (
    FMI_VERSIONS,
    MODEL_IDENTIFIER,
    build_description,
    fmu_header,
    model_description,
)
from bushenv.export.facts import (
    Facts,
    facts_of,
    find_card,
)
from bushenv.export.flagged import Carried
from bushenv.export.model_c import BOUCWEN_SUBSTEPS, EXPORTABLE_BY_COORDS, model_source
from bushenv.models import ModelError, ModelSpec, file_hash, get_model, model_file
from bushenv.persist import atomic_write, json_text

CFLAGS = ("-shared", "-fPIC", "-O2", "-std=c99", "-ffp-contract=off", "-fvisibility=hidden")
# The C of an FMU: bushenv's own in c/, the FMI standard's headers vendored unchanged in
# vendor/fmi/ (2-clause BSD, Modelica Association: vendor/fmi/LICENSE.txt). All of them sit
# side by side where the compiler runs and under the FMU's sources/.
HEADERS = ("core.h", "variables.h")
FMI_HEADERS = {
    "2.0": ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h", "fmi2_me.h"),
    "3.0": (
        "fmi3Functions.h",
        "fmi3FunctionTypes.h",
        "fmi3PlatformTypes.h",
        "fmi3_me.h",
        "fmi3_stubs.h",
    ),
}
FMI_STANDARD_HEADERS = frozenset(
    {
        "fmi2Functions.h",
        "fmi2FunctionTypes.h",
        "fmi2TypesPlatform.h",
        "fmi3Functions.h",
        "fmi3FunctionTypes.h",
        "fmi3PlatformTypes.h",
    }
)
INSTALL_HINT = (
    "install one (Debian/Ubuntu: apt-get install gcc; Fedora: dnf install gcc; macOS: "
    "xcode-select --install) or name it in $CC"
)


class ExportError(BadInput):
    """The model cannot be exported as asked; the message names what and how to fix it."""


@dataclass(frozen=True)
class Exported:
    path: Path
    fmi_version: str
    model: str
    facts: Facts
    compiler: str
    coords: int = 1

    @property
    def certificate(self) -> Carried | None:
        return self.facts.certificate


class FailingCertificate(ExportError):
    """The model fails its certificate and ``allow_failing`` was not given."""


def refusal(model_label: str, cert: Carried) -> str:
    """Why a model that fails its certificate is refused, and how to export it anyway."""
    return (
        f"{model_label} fails its certificate: {cert.failing or 'holds'}, flagged ranges "
        f"{cert.ranges_text()} ({cert.source}). Not exported: its force there is not to be "
        "trusted. Pass --allow-failing to export it anyway (the FMU carries the ranges, raises "
        "in_flagged_range inside them and logs a warning), or see the holds with bushenv "
        "certify MODEL"
    )


def c_compiler() -> str:
    """The C compiler to use: $CC if set, else ``cc``, else ``gcc`` (full path)."""
    wanted = os.environ.get("CC", "").strip()
    names = [wanted] if wanted else ["cc", "gcc"]
    for name in names:
        found = shutil.which(name)
        if found:
            return found
    looked = f"$CC={wanted!r}" if wanted else "'cc' and 'gcc' on PATH"
    raise ExportError(f"no C compiler found (looked for {looked}); {INSTALL_HINT}")


def platform_folders() -> dict[str, str]:
    """binaries/ sub-folder per FMI version for this machine."""
    machine = platform.machine().lower()
    arch = {"amd64": "x86_64", "arm64": "aarch64"}.get(machine, machine)
    system = platform.system()
    if system == "Linux":
        return {"2.0": "linux64" if arch == "x86_64" else f"{arch}-linux", "3.0": f"{arch}-linux"}
    if system == "Darwin":
        return {"2.0": "darwin64", "3.0": f"{arch}-darwin"}
    raise ExportError(f"exporting on {system} is not supported here (Linux and macOS are)")


def _c_file(name: str) -> bytes:
    """One C file of the FMU: an FMI standard header from vendor/fmi/, bushenv's own from c/."""
    here = resources.files("bushenv.export")
    folder = here / "vendor" / "fmi" if name in FMI_STANDARD_HEADERS else here / "c"
    return (folder / name).read_bytes()


def _check_out(out: Path) -> None:
    parent = out.parent if str(out.parent) else Path(".")
    if out.suffix != ".fmu":
        raise ExportError(f"{out}: the output file must end in .fmu")
    if not parent.is_dir():
        raise ExportError(f"{out}: folder {parent} does not exist; create it or choose --out")
    if not os.access(parent, os.W_OK):
        raise ExportError(f"{out}: folder {parent} is not writable; choose another --out")


def compile_library(sources: dict[str, bytes], main: str, compiler: str, work: Path) -> bytes:
    """Compile ``main`` (with the other ``sources`` beside it) to a shared library's bytes."""
    for name, data in sources.items():
        (work / name).write_bytes(data)
    lib = work / f"{MODEL_IDENTIFIER}.so"
    cmd = [compiler, *CFLAGS, "-o", str(lib), str(work / main), "-lm"]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    except OSError as exc:
        raise ExportError(f"cannot run the C compiler {compiler}: {exc}; {INSTALL_HINT}") from None
    if done.returncode != 0:
        first = (done.stderr.strip().splitlines() or ["no message"])[0]
        raise ExportError(f"the C compiler {compiler} failed on {main}: {first}")
    return lib.read_bytes()


def export_fmu(
    spec: ModelSpec,
    out: str | os.PathLike,
    fmi_version: str = "2.0",
    axis: str = "axial",
    card: str | os.PathLike | None = None,
    certificate: str | os.PathLike | None = None,
    stroke_m: float | None = None,
    velocity_m_per_s: float | None = None,
    substeps: int = BOUCWEN_SUBSTEPS,
    coords: int | None = None,
    reference: str | os.PathLike | None = None,
    allow_failing: bool = False,
) -> Exported:
    """Write ``out`` (.fmu): ``spec`` (a registered name, a model file or a model) as compiled C.

    ``card``: the model card (default: ``MODEL.card.json`` beside a model file, if any);
    ``certificate``: a ``certificate.json`` of ``bushenv certify`` of this model (default: a
    NARX model is certified here, against ``reference`` if given, else without one);
    ``allow_failing``: export a model that fails its certificate (else FailingCertificate);
    ``stroke_m``,
    ``velocity_m_per_s``: the envelope instead of the card's; ``substeps``: Bouc-Wen RK4
    sub-steps per sample; ``coords``: the number of coordinates a registered name is built
    over (None: a file's or a model's own, a name's one). The FMU has one input and one output
    per coordinate. Raises ExportError / ModelError naming the problem.
    """
    from bushenv import __version__

    if fmi_version not in FMI_VERSIONS:
        raise ExportError(f"unknown FMI version {fmi_version!r}; known: {', '.join(FMI_VERSIONS)}")
    out = Path(out)
    _check_out(out)
    model = get_model(spec, axis=axis, coords=coords, wanted_by="bushenv export")
    kinds = EXPORTABLE_BY_COORDS.get(model.n_coords, ())
    if model.name not in kinds:
        over = "" if model.n_coords == 1 else f" over {model.n_coords} coordinates"
        raise ExportError(
            f"cannot export a {type(model).__name__} ({model.name!r} model{over}); exportable "
            f"kinds{over}: {', '.join(kinds) or 'none'}"
        )
    folders = platform_folders()
    compiler = c_compiler()
    path = model_file(spec, axis)
    card_path = Path(card) if card is not None else None
    if card_path is None:
        card_path = find_card(spec, axis)
    if card_path is not None and not card_path.is_file():
        raise ExportError(f"{card_path}: no such model card")
    cert = carried_certificate(
        model,
        spec,
        axis,
        path=certificate,
        reference=reference,
        stroke_m=stroke_m,
    )
    if cert.fails and not allow_failing:
        label = str(spec) if isinstance(spec, str | os.PathLike) else f"the {model.name!r} model"
        raise FailingCertificate(refusal(label, cert))
    facts = facts_of(
        model,
        file_hash(path) if path is not None and path.is_file() else None,
        card_path,
        cert,
        stroke_m,
        velocity_m_per_s,
    )
    body = model_source(model, substeps)
    token = (
        "{"
        + str(
            uuid.UUID(hashlib.sha256(f"{fmi_version}\n{body}\n{facts}".encode()).hexdigest()[:32])
        )
        + "}"
    )
    model_h = body + fmu_header(token, facts, model.n_coords)
    main = "fmi2.c" if fmi_version == "2.0" else "fmi3.c"
    sources = {"model.h": model_h.encode(), main: _c_file(main)}
    for name in HEADERS + FMI_HEADERS[fmi_version]:
        sources[name] = _c_file(name)
    with tempfile.TemporaryDirectory(prefix="bushenv-fmu-") as tmp:
        binary = compile_library(sources, main, compiler, Path(tmp))
    tool = f"bushenv {__version__}"
    description = model_description(
        fmi_version, model.name, token, facts, model.dt, tool, model.n_coords
    )
    files = {"modelDescription.xml": description.encode()}
    files[f"binaries/{folders[fmi_version]}/{MODEL_IDENTIFIER}.so"] = binary
    for name, data in sources.items():
        files[f"sources/{name}"] = data
    if fmi_version == "3.0":
        files["sources/buildDescription.xml"] = build_description().encode()
    if card_path is not None:
        files["documentation/card.json"] = card_path.read_bytes()
    if certificate is not None:
        files["documentation/certificate.json"] = Path(certificate).read_bytes()
    elif cert.document is not None:
        files["documentation/certificate.json"] = json_text(cert.document).encode()

    def write(fh) -> None:
        with zipfile.ZipFile(fh, "w", zipfile.ZIP_DEFLATED) as zf:
            for name, data in files.items():
                zf.writestr(name, data)

    try:
        atomic_write(out, write)
    except OSError as exc:
        raise ExportError(
            f"{out}: cannot write into {out.parent} ({exc.strerror}; a read-only folder?); "
            "choose another --out"
        ) from None
    return Exported(out, fmi_version, model.name, facts, compiler, model.n_coords)


__all__ = [
    "ExportError",
    "Exported",
    "FailingCertificate",
    "ModelError",
    "c_compiler",
    "export_fmu",
]
