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
    derivative_of: int | None = None  # vr of the state this is the derivative of


STATES = ("y", "w", "z1", "z2")  # seed 002 eqs. 1-4, model exchange (value references 10-13)
# where eqs. 1-2 switch (sgn d sgn z): relative velocities d1, d2 and z1, z2 (references 18-21)
INDICATORS = ("d1", "d2", "z1", "z2")
UNIT_OF = {"d1": "m/s", "d2": "m/s", "z1": "m", "z2": "m"}


def variables(has_velocity: bool, facts: Facts, dt: float, ode: bool = False) -> list[Variable]:
    """The FMU's variables; ``ode``: the model is an ODE (model exchange too): the force is
    continuous and the states and their derivatives are listed."""
    env = facts.envelope
    changes = "continuous" if ode else "discrete"
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
            changes,
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
            changes,
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
    if ode:
        for i, name in enumerate(STATES):
            unit = "m"
            out.append(
                Variable(
                    f"state.{name}",
                    10 + i,
                    "Real",
                    "local",
                    "continuous",
                    f"seed 002 eqs. 1-4: {name}",
                    unit,
                    "0.0",
                )
            )
        for i, name in enumerate(STATES):
            out.append(
                Variable(
                    f"der(state.{name})",
                    14 + i,
                    "Real",
                    "local",
                    "continuous",
                    f"d{name}/dt",
                    "m/s",
                    None,
                    10 + i,
                )
            )
        for i, name in enumerate(INDICATORS):
            out.append(
                Variable(
                    f"event.{name}",
                    18 + i,
                    "Real",
                    "local",
                    "continuous",
                    f"event indicator: {name} changes sign",
                    UNIT_OF[name],
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
    has_velocity: bool,
    facts: Facts,
    dt: float,
    tool: str,
    ode: bool = False,
) -> str:
    """modelDescription.xml for FMI ``version``: co-simulation, and model exchange if ``ode``."""
    vs = variables(has_velocity, facts, dt, ode)
    now = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    head = _attr(
        fmiVersion=version,
        modelName=f"bushenv_{kind}",
        description=f"bushenv {kind!r} bushing model, compiled C at {1 / dt:.6g} Hz",
        generationTool=tool,
        generationDateAndTime=now,
        variableNamingConvention="structured",
    )
    make = _fmi2 if version == "2.0" else _fmi3
    return (
        "\n".join(['<?xml version="1.0" encoding="UTF-8"?>', *make(vs, head, token, dt, ode)])
        + "\n"
    )


def _fmi2(vs: list[Variable], head: str, token: str, dt: float, ode: bool) -> list[str]:
    idx = {v.vr: i + 1 for i, v in enumerate(vs)}
    # outputs of an ODE model depend on the states too: no list (= on every known)
    deps = (
        ""
        if ode
        else _attr(dependencies=" ".join(str(idx[v.vr]) for v in vs if v.causality == "input"))
    )
    src = '<SourceFiles><File name="fmi2.c"/></SourceFiles>'
    n_ind = len(INDICATORS) if ode else 0
    lines = [f'<fmiModelDescription{head} guid="{token}" numberOfEventIndicators="{n_ind}">']
    if ode:
        lines.append(f'  <ModelExchange modelIdentifier="{MODEL_IDENTIFIER}">{src}</ModelExchange>')
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
        der = idx[v.derivative_of] if v.derivative_of is not None else None
        lines.append(
            f"    <ScalarVariable{attrs}>"
            f"<{v.kind}{_attr(unit=v.unit, start=v.start, derivative=der)}/>"
            "</ScalarVariable>"
        )
    outs = [idx[v.vr] for v in vs if v.causality == "output"]
    ders = [idx[v.vr] for v in vs if v.derivative_of is not None]
    lines += ["  </ModelVariables>", "  <ModelStructure>", "    <Outputs>"]
    lines += [f'      <Unknown index="{i}"{deps}/>' for i in outs]
    lines += ["    </Outputs>"]
    if ders:
        lines += [
            "    <Derivatives>",
            *[f'      <Unknown index="{i}"/>' for i in ders],
            "    </Derivatives>",
        ]
    lines += ["    <InitialUnknowns>"]
    lines += [f'      <Unknown index="{i}"{deps}/>' for i in sorted(outs + ders)]
    lines += ["    </InitialUnknowns>", "  </ModelStructure>", "</fmiModelDescription>"]
    return lines


def _fmi3(vs: list[Variable], head: str, token: str, dt: float, ode: bool) -> list[str]:
    deps = (
        "" if ode else _attr(dependencies=" ".join(str(v.vr) for v in vs if v.causality == "input"))
    )
    lines = [f'<fmiModelDescription{head} instantiationToken="{token}">']
    if ode:
        lines.append(
            f'  <ModelExchange modelIdentifier="{MODEL_IDENTIFIER}"'
            ' needsCompletedIntegratorStep="true"/>'
        )
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
            derivative=v.derivative_of,
        )
        if v.kind == "String" and v.start is not None:
            lines.append(f"    <{tag}{attrs}><Start value={quoteattr(v.start)}/></{tag}>")
        else:
            lines.append(f"    <{tag}{attrs}{_attr(start=v.start)}/>")
    outs = [v.vr for v in vs if v.causality == "output"]
    ders = [v.vr for v in vs if v.derivative_of is not None]
    lines += ["  </ModelVariables>", "  <ModelStructure>"]
    lines += [f'    <Output valueReference="{vr}"{deps}/>' for vr in outs]
    lines += [f'    <ContinuousStateDerivative valueReference="{vr}"/>' for vr in ders]
    lines += [f'    <InitialUnknown valueReference="{vr}"{deps}/>' for vr in outs + ders]
    lines += [f'    <EventIndicator valueReference="{v.vr}"/>' for v in vs if v.vr in range(18, 22)]
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
