"""modelDescription.xml (FMI 2.0 and 3.0), buildDescription.xml (3.0) and the generated
``fmu.h`` that ties the C to them (token, envelope, facts).

Every FMU has one interface, whatever the model kind, in co-simulation and model exchange.
Value references: 0 time (FMI 3), 4 outside_envelope, 5 time_outside_envelope_s [s], 8 the
sample time, 9 in_flagged_range (the certificate's boxes), 100.. the facts; per coordinate
(``PORTS``) its input, optional velocity input
(used once the master connects it), force output and envelope constants: one axis 1
deflection [m], 2 velocity [m/s], 3 force [N], 6-7 the envelope; three axes 30-45.
"""

from __future__ import annotations

import datetime
from dataclasses import dataclass
from xml.sax.saxutils import escape, quoteattr

from bushenv.export.facts import Facts
from bushenv.export.model_c import lit

MODEL_IDENTIFIER = "bushing"
# The FMU's interface version (modelDescription's ``version``), raised when what a master sees
# changes. 1: the velocity input required by linear, hybrid and boucwen, none on nn, Bouc-Wen
# alone in model exchange (states y, w, z1, z2). 2: one interface for every kind, the velocity
# optional (the FMU's own backward difference otherwise), every kind in model exchange.
INTERFACE_VERSION = "2"
FMI_VERSIONS = ("2.0", "3.0")
UNITS = {
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "N": {"kg": 1, "m": 1, "s": -2},
    "s": {"s": 1},
    "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1},
    "N.m": {"kg": 1, "m": 2, "s": -2},
}


@dataclass(frozen=True)
class Port:
    """One coordinate's variables: its input, velocity input, force output and envelope
    constants, with their value references."""

    x: str
    x_unit: str
    x_text: str
    v: str
    v_unit: str
    f: str
    f_unit: str
    stroke: str
    rate: str
    symbol: str  # in messages
    vr_x: int
    vr_v: int
    vr_f: int
    vr_stroke: int
    vr_rate: int


# One coordinate: the references of interface version 1 kept. Three (axial, radial, rotation,
# as bushenv's three-axis models order them): references 30-45.
PORTS = {
    1: (
        Port("deflection", "m", "bushing deflection along its axis", "velocity", "m/s", "force",
             "N", "envelope_stroke_m", "envelope_velocity_m_per_s", "x", 1, 2, 3, 6, 7),
    ),
    3: (
        Port("deflection_axial", "m", "axial deflection", "velocity_axial", "m/s",
             "force_axial", "N", "envelope_stroke_axial_m", "envelope_velocity_axial_m_per_s",
             "x_axial", 30, 33, 36, 40, 43),
        Port("deflection_radial", "m", "radial deflection", "velocity_radial", "m/s",
             "force_radial", "N", "envelope_stroke_radial_m", "envelope_velocity_radial_m_per_s",
             "x_radial", 31, 34, 37, 41, 44),
        Port("rotation", "rad", "rotation, the third coordinate of bushenv's three-axis models",
             "rotation_rate", "rad/s", "moment", "N.m", "envelope_rotation_rad",
             "envelope_rotation_rate_rad_per_s", "theta", 32, 35, 38, 42, 45),
    ),
}  # fmt: skip


@dataclass(frozen=True)
class Variable:
    name: str
    vr: int
    kind: str  # "Real", "Boolean", "String"
    causality: str
    variability: str
    description: str
    unit: str | None = None
    start: str | None = None


def variables(facts: Facts, dt: float, coords: int = 1) -> list[Variable]:
    """The FMU's variables over ``coords`` coordinates. The forces are continuous (in model
    exchange they follow the current input between samples); the envelope's outputs change at
    samples only."""
    ports = PORTS[coords]
    strokes, rates = facts.envelope.limits(coords)
    out = [
        Variable(p.x, p.vr_x, "Real", "input", "continuous", p.x_text, p.x_unit, "0.0")
        for p in ports
    ]
    out += [
        Variable(
            p.v,
            p.vr_v,
            "Real",
            "input",
            "continuous",
            f"rate of {p.x}; optional: once set after initialisation it replaces the FMU's own "
            "backward difference",
            p.v_unit,
            "0.0",
        )
        for p in ports
    ]
    out += [
        Variable(
            p.f,
            p.vr_f,
            "Real",
            "output",
            "continuous",
            f"bushing {p.f.split('_')[0]}: co-simulation, of the latest model sample; model "
            "exchange, of the current input (between samples)",
            p.f_unit,
        )
        for p in ports
    ]
    out += [
        Variable(
            "outside_envelope",
            4,
            "Boolean",
            "output",
            "discrete",
            "the latest sample's input lies outside the validity envelope",
        ),
        Variable(
            "time_outside_envelope_s",
            5,
            "Real",
            "output",
            "discrete",
            "time the input has spent outside the validity envelope",
            "s",
        ),
        Variable(
            "in_flagged_range",
            9,
            "Boolean",
            "output",
            "discrete",
            "the latest sample's input lies in a range where the model fails its certificate "
            "(card.certificate_flagged)",
        ),
    ]
    for p, stroke, rate in zip(ports, strokes, rates, strict=True):
        out.append(
            Variable(p.stroke, p.vr_stroke, "Real", "local", "constant",
                     f"largest |{p.x}| of the envelope", p.x_unit, lit(stroke))
        )  # fmt: skip
        out.append(
            Variable(p.rate, p.vr_rate, "Real", "local", "constant",
                     f"largest |{p.v}| of the envelope", p.v_unit, lit(rate))
        )  # fmt: skip
    out.append(
        Variable(
            "sample_time_s",
            8,
            "Real",
            "local",
            "constant",
            "the model's own sample time",
            "s",
            lit(dt),
        )
    )
    for i, (name, value) in enumerate(facts.lines):
        out.append(
            Variable(
                f"card.{name}",
                100 + i,
                "String",
                "local",
                "constant",
                "model card fact",
                None,
                value,
            )
        )
    return out


def _attr(**kw) -> str:
    return "".join(f" {k}={quoteattr(str(v))}" for k, v in kw.items() if v is not None)


def _units() -> list[str]:
    lines = ["  <UnitDefinitions>"]
    for name, base in UNITS.items():
        lines.append(f"    <Unit name={quoteattr(name)}><BaseUnit{_attr(**base)}/></Unit>")
    return lines + ["  </UnitDefinitions>"]


def _log_categories() -> list[str]:
    cats = ("logStatusWarning", "logStatusError", "logAll")
    return [
        "  <LogCategories>",
        *[f'    <Category name="{c}"/>' for c in cats],
        "  </LogCategories>",
    ]


def _card_xml(lines: list[tuple[str, str]]) -> str:
    items = "".join(f"<Fact name={quoteattr(n)}>{escape(v)}</Fact>" for n, v in lines)
    return f"<Card>{items}</Card>"


def model_description(
    version: str,
    kind: str,
    token: str,
    facts: Facts,
    dt: float,
    tool: str,
    coords: int = 1,
) -> str:
    """modelDescription.xml for FMI ``version``: co-simulation and model exchange."""
    vs = variables(facts, dt, coords)
    now = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    head = _attr(
        fmiVersion=version,
        modelName=f"bushenv_{kind}",
        description=f"bushenv {kind!r} bushing model, compiled C at {1 / dt:.6g} Hz",
        version=INTERFACE_VERSION,
        generationTool=tool,
        generationDateAndTime=now,
        variableNamingConvention="structured",
    )
    make = _fmi2 if version == "2.0" else _fmi3
    return "\n".join(['<?xml version="1.0" encoding="UTF-8"?>', *make(vs, head, token, dt)]) + "\n"


def _fmi2(vs: list[Variable], head: str, token: str, dt: float) -> list[str]:
    idx = {v.vr: i + 1 for i, v in enumerate(vs)}
    deps = _attr(dependencies=" ".join(str(idx[v.vr]) for v in vs if v.causality == "input"))
    src = '<SourceFiles><File name="fmi2.c"/></SourceFiles>'
    lines = [
        f'<fmiModelDescription{head} guid="{token}" numberOfEventIndicators="0">',
        f'  <ModelExchange modelIdentifier="{MODEL_IDENTIFIER}">{src}</ModelExchange>',
    ]
    lines += [
        f'  <CoSimulation modelIdentifier="{MODEL_IDENTIFIER}"'
        ' canHandleVariableCommunicationStepSize="true" canInterpolateInputs="true"'
        f' maxOutputDerivativeOrder="0">{src}</CoSimulation>',
        *_units(),
        *_log_categories(),
        f'  <DefaultExperiment startTime="0.0" stepSize="{lit(dt)}"/>',
        f'  <VendorAnnotations><Tool name="bushenv">{_card_xml(facts_of_lines(vs))}</Tool>'
        "</VendorAnnotations>",
        "  <ModelVariables>",
    ]
    for v in vs:
        exact = v.variability == "constant" or (v.start is not None and v.causality == "local")
        attrs = _attr(
            name=v.name,
            valueReference=v.vr,
            description=v.description,
            causality=v.causality,
            variability=v.variability,
            initial="exact" if exact else None,
        )
        lines.append(
            f"    <ScalarVariable{attrs}>"
            f"<{v.kind}{_attr(unit=v.unit, start=v.start)}/>"
            "</ScalarVariable>"
        )
    outs = [idx[v.vr] for v in vs if v.causality == "output"]
    lines += ["  </ModelVariables>", "  <ModelStructure>", "    <Outputs>"]
    lines += [f'      <Unknown index="{i}"{deps}/>' for i in outs]
    lines += ["    </Outputs>", "    <InitialUnknowns>"]
    lines += [f'      <Unknown index="{i}"{deps}/>' for i in outs]
    lines += ["    </InitialUnknowns>", "  </ModelStructure>", "</fmiModelDescription>"]
    return lines


def _fmi3(vs: list[Variable], head: str, token: str, dt: float) -> list[str]:
    deps = _attr(dependencies=" ".join(str(v.vr) for v in vs if v.causality == "input"))
    lines = [
        f'<fmiModelDescription{head} instantiationToken="{token}">',
        f'  <ModelExchange modelIdentifier="{MODEL_IDENTIFIER}"'
        ' needsCompletedIntegratorStep="false"/>',
    ]
    lines += [
        f'  <CoSimulation modelIdentifier="{MODEL_IDENTIFIER}"'
        ' canHandleVariableCommunicationStepSize="true" hasEventMode="false"'
        f' fixedInternalStepSize="{lit(dt)}" providesIntermediateUpdate="false"/>',
        *_units(),
        *_log_categories(),
        f'  <DefaultExperiment startTime="0.0" stepSize="{lit(dt)}"/>',
        "  <ModelVariables>",
        '    <Float64 name="time" valueReference="0" causality="independent"'
        ' variability="continuous" description="simulation time" unit="s"/>',
    ]
    for v in vs:
        tag = {"Real": "Float64", "Boolean": "Boolean", "String": "String"}[v.kind]
        exact = v.variability != "constant" and v.start is not None and v.causality == "local"
        attrs = _attr(
            name=v.name,
            valueReference=v.vr,
            description=v.description,
            causality=v.causality,
            variability=v.variability,
            initial="exact" if exact else None,
            unit=v.unit,
        )
        if v.kind == "String" and v.start is not None:
            lines.append(f"    <{tag}{attrs}><Start value={quoteattr(v.start)}/></{tag}>")
        else:
            lines.append(f"    <{tag}{attrs}{_attr(start=v.start)}/>")
    outs = [v.vr for v in vs if v.causality == "output"]
    lines += ["  </ModelVariables>", "  <ModelStructure>"]
    lines += [f'    <Output valueReference="{vr}"{deps}/>' for vr in outs]
    lines += [f'    <InitialUnknown valueReference="{vr}"{deps}/>' for vr in outs]
    lines += [
        "  </ModelStructure>",
        '  <Annotations><Annotation type="org.bushenv.card">'
        f"{_card_xml(facts_of_lines(vs))}</Annotation></Annotations>",
        "</fmiModelDescription>",
    ]
    return lines


def facts_of_lines(vs: list[Variable]) -> list[tuple[str, str]]:
    """The card's facts back from their string constants (the annotation repeats them)."""
    return [(v.name.removeprefix("card."), v.start or "") for v in vs if v.kind == "String"]


def build_description() -> str:
    """sources/buildDescription.xml (FMI 3.0): one C file, headers beside it."""
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n<fmiBuildDescription fmiVersion="3.0">\n'
        f'  <BuildConfiguration modelIdentifier="{MODEL_IDENTIFIER}">\n'
        '    <SourceFileSet language="C99">\n      <SourceFile name="fmi3.c"/>\n'
        "    </SourceFileSet>\n  </BuildConfiguration>\n</fmiBuildDescription>\n"
    )


def _c_string(text: str) -> str:
    """A C string literal of ``text`` (UTF-8; escapes, no hex escape running into the next)."""
    out = []
    for b in text.encode("utf-8"):
        ch = chr(b)
        if ch in '"\\':
            out.append("\\" + ch)
        elif 32 <= b < 127:
            out.append(ch)
        else:
            out.append(f'\\x{b:02x}""')
    return '"' + "".join(out) + '"'


def _c_array(kind: str, name: str, values) -> str:
    return f"static const {kind} {name}[] = {{{', '.join(values)}}};"


def fmu_header(token: str, facts: Facts, coords: int = 1) -> str:
    """The generated constants ``core.h`` and ``variables.h`` read (appended to model.h)."""
    env = facts.envelope
    ports = PORTS[coords]
    strokes, rates = env.limits(coords)
    # each box: its lower corner, then its upper corner, one value per coordinate
    flagged = [lit(v) for b in env.flagged for v in (*b.lo, *b.hi)] or ["0.0"]
    why = [_c_string(b.why) for b in env.flagged] or ['""']
    facts_c = ", ".join(_c_string(v) for _, v in facts.lines) or '""'
    cert = facts.certificate
    lines = [
        f'#define FMU_TOKEN "{token}"',
        "#define HAS_VELOCITY 1 /* every FMU has the (optional) velocity inputs */",
        _c_array("double", "ENV_STROKE", [lit(v) for v in strokes]),
        _c_array("double", "ENV_VELOCITY", [lit(v) for v in rates]),
        f"#define ENV_N_FLAGGED {len(env.flagged)}",
        _c_array("double", "ENV_FLAGGED", flagged),
        _c_array("char *const", "ENV_FLAGGED_WHY", why),
        f"#define CERT_FAILS {int(cert is not None and cert.fails)}",
        f"#define CERT_VERDICT {_c_string('' if cert is None else cert.verdict())}",
        f"#define ENV_SOURCE {_c_string(env.source)}",
        f"#define N_FACTS {len(facts.lines)}",
        f"static const char *const FACTS[] = {{{facts_c}}};",
    ]
    for name, values in (
        ("COORD_NAMES", [p.x for p in ports]),
        ("COORD_SYMBOLS", [p.symbol for p in ports]),
        ("COORD_UNITS", [p.x_unit for p in ports]),
        ("FORCE_NAMES", [p.f for p in ports]),
    ):
        lines.append(_c_array("char *const", name, [_c_string(v) for v in values]))
    for name, attr in (
        ("VR_X", "vr_x"),
        ("VR_V", "vr_v"),
        ("VR_F", "vr_f"),
        ("VR_STROKE_OF", "vr_stroke"),
        ("VR_RATE_OF", "vr_rate"),
    ):
        lines.append(_c_array("unsigned", name, [str(getattr(p, attr)) for p in ports]))
    if coords == 1:  # the names of interface version 1 (scripts/bench_fmu.py's harness)
        lines += ["#define VR_DEFLECTION 1", "#define VR_VELOCITY 2", "#define VR_FORCE 3"]
    return "\n".join(lines) + "\n"
