"""modelDescription.xml (FMI 2.0 and 3.0), buildDescription.xml (3.0) and the generated
``fmu.h`` that ties the C to them (token, velocity input or not, envelope, facts).

Value references are fixed (``c/variables.h``): 0 time (FMI 3), 1 deflection [m], 2 velocity
[m/s] (models that use it), 3 force [N], 4 outside_envelope, 5 time_outside_envelope_s [s],
6-8 the envelope's stroke and velocity and the sample time (constants), 100.. the facts.
"""

from __future__ import annotations

import datetime
from dataclasses import dataclass
from xml.sax.saxutils import escape, quoteattr

from bushenv.export.facts import Facts
from bushenv.export.model_c import lit

MODEL_IDENTIFIER = "bushing"
FMI_VERSIONS = ("2.0", "3.0")
UNITS = {"m": {"m": 1}, "m/s": {"m": 1, "s": -1}, "N": {"kg": 1, "m": 1, "s": -2}, "s": {"s": 1}}


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


def variables(has_velocity: bool, facts: Facts, dt: float) -> list[Variable]:
    env = facts.envelope
    out = [
        Variable(
            "deflection",
            1,
            "Real",
            "input",
            "continuous",
            "bushing deflection along its axis",
            "m",
            "0.0",
        ),
    ]
    if has_velocity:
        out.append(
            Variable("velocity", 2, "Real", "input", "continuous", "deflection rate", "m/s", "0.0")
        )
    out += [
        Variable(
            "force",
            3,
            "Real",
            "output",
            "discrete",
            "bushing force of the latest model sample",
            "N",
        ),
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
            "envelope_stroke_m",
            6,
            "Real",
            "local",
            "constant",
            "largest |deflection| of the envelope",
            "m",
            lit(env.stroke_m),
        ),
        Variable(
            "envelope_velocity_m_per_s",
            7,
            "Real",
            "local",
            "constant",
            "largest |velocity| of the envelope",
            "m/s",
            lit(env.velocity_m_per_s),
        ),
        Variable(
            "sample_time_s",
            8,
            "Real",
            "local",
            "constant",
            "the model's own sample time",
            "s",
            lit(dt),
        ),
    ]
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


def _card_xml(facts: Facts) -> str:
    items = "".join(f"<Fact name={quoteattr(n)}>{escape(v)}</Fact>" for n, v in facts.lines)
    return f"<Card>{items}</Card>"


def model_description(
    version: str, kind: str, token: str, has_velocity: bool, facts: Facts, dt: float, tool: str
) -> str:
    """modelDescription.xml for FMI ``version`` (co-simulation)."""
    vs = variables(has_velocity, facts, dt)
    now = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    head = _attr(
        fmiVersion=version,
        modelName=f"bushenv_{kind}",
        description=f"bushenv {kind!r} bushing model, compiled C at {1 / dt:.6g} Hz",
        generationTool=tool,
        generationDateAndTime=now,
        variableNamingConvention="structured",
    )
    inputs = " ".join(str(v.vr) for v in vs if v.causality == "input")
    outs = [v for v in vs if v.causality == "output"]
    if version == "2.0":
        idx = {v.vr: i + 1 for i, v in enumerate(vs)}
        in_idx = " ".join(str(idx[v.vr]) for v in vs if v.causality == "input")
        lines = [
            '<?xml version="1.0" encoding="UTF-8"?>',
            f'<fmiModelDescription{head} guid="{token}" numberOfEventIndicators="0">',
            f'  <CoSimulation modelIdentifier="{MODEL_IDENTIFIER}"'
            ' canHandleVariableCommunicationStepSize="true" canInterpolateInputs="true"'
            ' maxOutputDerivativeOrder="0">',
            '    <SourceFiles><File name="fmi2.c"/></SourceFiles>',
            "  </CoSimulation>",
            *_units(),
            *_log_categories(),
            f'  <DefaultExperiment startTime="0.0" stepSize="{lit(dt)}"/>',
            f'  <VendorAnnotations><Tool name="bushenv">{_card_xml(facts)}</Tool>'
            "</VendorAnnotations>",
            "  <ModelVariables>",
        ]
        for v in vs:
            initial = "exact" if v.variability == "constant" else None
            lines.append(
                f"    <ScalarVariable{_attr(name=v.name, valueReference=v.vr, description=v.description, causality=v.causality, variability=v.variability, initial=initial)}>"  # noqa: E501
                f"<{v.kind}{_attr(unit=v.unit, start=v.start)}/></ScalarVariable>"
            )
        lines += ["  </ModelVariables>", "  <ModelStructure>", "    <Outputs>"]
        lines += [f'      <Unknown index="{idx[v.vr]}" dependencies="{in_idx}"/>' for v in outs]
        lines += ["    </Outputs>", "    <InitialUnknowns>"]
        lines += [f'      <Unknown index="{idx[v.vr]}" dependencies="{in_idx}"/>' for v in outs]
        lines += ["    </InitialUnknowns>", "  </ModelStructure>", "</fmiModelDescription>"]
        return "\n".join(lines) + "\n"
    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<fmiModelDescription{head} instantiationToken="{token}">',
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
        attrs = _attr(
            name=v.name,
            valueReference=v.vr,
            description=v.description,
            causality=v.causality,
            variability=v.variability,
            unit=v.unit,
        )
        if v.kind == "String" and v.start is not None:
            lines.append(f"    <{tag}{attrs}><Start value={quoteattr(v.start)}/></{tag}>")
        else:
            lines.append(f"    <{tag}{attrs}{_attr(start=v.start)}/>")
    lines += ["  </ModelVariables>", "  <ModelStructure>"]
    lines += [f'    <Output valueReference="{v.vr}" dependencies="{inputs}"/>' for v in outs]
    lines += [
        f'    <InitialUnknown valueReference="{v.vr}" dependencies="{inputs}"/>' for v in outs
    ]
    lines += [
        "  </ModelStructure>",
        f'  <Annotations><Annotation type="org.bushenv.card">{_card_xml(facts)}</Annotation>'
        "</Annotations>",
        "</fmiModelDescription>",
    ]
    return "\n".join(lines) + "\n"


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


def fmu_header(token: str, has_velocity: bool, facts: Facts) -> str:
    """The generated constants ``core.h`` and ``variables.h`` read (appended to model.h)."""
    env = facts.envelope
    flagged = [lit(v) for pair in env.flagged_m for v in pair] or ["0.0"]
    facts_c = ", ".join(_c_string(v) for _, v in facts.lines) or '""'
    return (
        "\n".join(
            [
                f'#define FMU_TOKEN "{token}"',
                f"#define HAS_VELOCITY {int(has_velocity)}",
                f"#define ENV_STROKE_M {lit(env.stroke_m)}",
                f"#define ENV_VELOCITY_M_PER_S {lit(env.velocity_m_per_s)}",
                f"#define ENV_N_FLAGGED {len(env.flagged_m)}",
                f"static const double ENV_FLAGGED[] = {{{', '.join(flagged)}}};",
                f"#define ENV_SOURCE {_c_string(env.source)}",
                f"#define N_FACTS {len(facts.lines)}",
                f"static const char *const FACTS[] = {{{facts_c}}};",
            ]
        )
        + "\n"
    )
