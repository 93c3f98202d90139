"""Variable tables: the single source of each FMU's interface.

Each model folder holds a ``variables.py`` with one :class:`Table`. The build derives from it
both the ``modelDescription.xml`` and the C header ``variables.h`` that the shell and the
model's equations use, so a variable is declared once, with its unit and description.

Value references are assigned per type in table order (FMI 2.0 numbers Real, Integer and
Boolean variables independently), which is also the index of the variable in the instance's
arrays ``real``, ``integer`` and ``boolean``.
"""

from __future__ import annotations

import math
import uuid
from dataclasses import dataclass, field
from xml.sax.saxutils import quoteattr

CAUSALITIES = ("parameter", "input", "output")
TYPES = ("Real", "Integer", "Boolean")


@dataclass(frozen=True)
class Variable:
    """One FMI variable.

    ``depends`` applies to outputs: ``None`` means the output depends on no input (it is a
    function of the state only), ``"all"`` means it depends on every input, and a tuple names
    the inputs it depends on directly (direct feedthrough).
    """

    name: str
    causality: str
    type: str = "Real"
    start: float | int | bool | None = None
    unit: str = ""
    description: str = ""
    min: float | None = None
    max: float | None = None
    variability: str | None = None
    depends: tuple[str, ...] | str | None = None

    def __post_init__(self):
        if self.causality not in CAUSALITIES:
            raise ValueError(f"{self.name}: causality {self.causality!r} not in {CAUSALITIES}")
        if self.type not in TYPES:
            raise ValueError(f"{self.name}: type {self.type!r} not in {TYPES}")
        if self.causality in ("parameter", "input") and self.start is None:
            raise ValueError(f"{self.name}: a {self.causality} needs a start value")
        if self.causality == "output" and self.start is not None:
            raise ValueError(f"{self.name}: outputs are calculated and take no start value")

    @property
    def fmi_variability(self) -> str:
        if self.variability:
            return self.variability
        if self.causality == "parameter":
            return "fixed"
        return "continuous" if self.type == "Real" else "discrete"


def Real(name, causality, start=None, unit="", description="", **kw) -> Variable:
    return Variable(name, causality, "Real", start, unit, description, **kw)


def Integer(name, causality, start=None, description="", **kw) -> Variable:
    return Variable(name, causality, "Integer", start, "", description, **kw)


def Boolean(name, causality, start=None, description="", **kw) -> Variable:
    return Variable(name, causality, "Boolean", start, "", description, **kw)


@dataclass
class Table:
    """The variables of one model, and what is derived from them."""

    model: str
    description: str
    variables: list[Variable]
    states: int = 0
    vr: dict[str, int] = field(init=False)

    def __post_init__(self):
        names = [v.name for v in self.variables]
        duplicated = {n for n in names if names.count(n) > 1}
        if duplicated:
            raise ValueError(f"{self.model}: variables declared twice: {sorted(duplicated)}")
        counters = dict.fromkeys(TYPES, 0)
        self.vr = {}
        for v in self.variables:
            self.vr[v.name] = counters[v.type]
            counters[v.type] += 1
        self.counts = counters
        inputs = {v.name for v in self.variables if v.causality == "input"}
        for v in self.variables:
            if isinstance(v.depends, tuple) and not set(v.depends) <= inputs:
                raise ValueError(f"{self.model}.{v.name} depends on unknown inputs {v.depends}")

    def of(self, causality: str, type_: str | None = None) -> list[Variable]:
        return [
            v for v in self.variables
            if v.causality == causality and (type_ is None or v.type == type_)
        ]

    @property
    def guid(self) -> str:
        # Stable for a given interface: a rebuild with the same table keeps the GUID.
        text = "|".join(f"{v.name}:{v.causality}:{v.type}" for v in self.variables)
        return "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, f"quadcosim/{self.model}/{text}")) + "}"

    # ----------------------------------------------------------------- modelDescription.xml
    def model_description(self, source_files: list[str]) -> str:
        index = {v.name: i + 1 for i, v in enumerate(self.variables)}
        inputs = [v.name for v in self.variables if v.causality == "input"]
        units = sorted({v.unit for v in self.variables if v.unit})
        lines = [
            '<?xml version="1.0" encoding="UTF-8"?>',
            "<fmiModelDescription",
            '  fmiVersion="2.0"',
            f'  modelName="{self.model}"',
            f'  guid="{self.guid}"',
            f"  description={quoteattr(self.description)}",
            '  generationTool="quadcosim fmus.build"',
            '  variableNamingConvention="flat"',
            '  numberOfEventIndicators="0">',
            f'  <CoSimulation modelIdentifier="{self.model}" canHandleVariableCommunicationStepSize="true"'
            ' canNotUseMemoryManagementFunctions="true">',
            "    <SourceFiles>",
            *[f'      <File name="{name}"/>' for name in source_files],
            "    </SourceFiles>",
            "  </CoSimulation>",
        ]
        if units:
            lines.append("  <UnitDefinitions>")
            lines += [f'    <Unit name="{u}"/>' for u in units]
            lines.append("  </UnitDefinitions>")
        lines.append('  <DefaultExperiment startTime="0" stopTime="2" stepSize="0.001"/>')
        lines.append("  <ModelVariables>")
        for v in self.variables:
            attrs = [
                f'name="{v.name}"',
                f'valueReference="{self.vr[v.name]}"',
                f'causality="{v.causality}"',
                f'variability="{v.fmi_variability}"',
            ]
            if v.causality == "parameter":
                attrs.append('initial="exact"')
            if v.description:
                attrs.append(f"description={quoteattr(v.description)}")
            type_attrs = []
            if v.start is not None:
                type_attrs.append(f'start="{_xml_value(v.type, v.start)}"')
            if v.unit:
                type_attrs.append(f'unit="{v.unit}"')
            if v.min is not None:
                type_attrs.append(f'min="{v.min!r}"')
            if v.max is not None:
                type_attrs.append(f'max="{v.max!r}"')
            lines.append(f"    <!-- {index[v.name]} -->")
            lines.append(f"    <ScalarVariable {' '.join(attrs)}>")
            lines.append(f"      <{v.type} {' '.join(type_attrs)}/>".replace(" />", "/>"))
            lines.append("    </ScalarVariable>")
        lines.append("  </ModelVariables>")
        lines.append("  <ModelStructure>")
        outputs = self.of("output")
        lines.append("    <Outputs>")
        for v in outputs:
            lines.append(f"      {_unknown(index[v.name], self._depends(v, inputs), index)}")
        lines.append("    </Outputs>")
        lines.append("    <InitialUnknowns>")
        for v in outputs:
            lines.append(f'      <Unknown index="{index[v.name]}"/>')
        lines.append("    </InitialUnknowns>")
        lines.append("  </ModelStructure>")
        lines.append("</fmiModelDescription>")
        return "\n".join(lines) + "\n"

    @staticmethod
    def _depends(v: Variable, inputs: list[str]) -> list[str]:
        if v.depends is None:
            return []
        if v.depends == "all":
            return inputs
        return list(v.depends)

    # ----------------------------------------------------------------- variables.h
    def c_header(self) -> str:
        lines = [
            f"/* Generated from fmus/{self.model}/variables.py by fmus.build: do not edit. */",
            "#ifndef VARIABLES_H",
            "#define VARIABLES_H",
            "",
            '#include "shell.h"',
            "",
            f'#define MODEL_NAME "{self.model}"',
            f'#define MODEL_GUID "{self.guid}"',
            f"#define N_REAL {self.counts['Real']}",
            f"#define N_INTEGER {self.counts['Integer']}",
            f"#define N_BOOLEAN {self.counts['Boolean']}",
            f"#define N_STATES {self.states}",
            "",
        ]
        for type_, prefix in (("Real", "VR_"), ("Integer", "VI_"), ("Boolean", "VB_")):
            members = [v for v in self.variables if v.type == type_]
            if members:
                lines.append("enum {")
                lines += [f"    {prefix}{v.name} = {self.vr[v.name]}," for v in members]
                lines.append("};")
        lines.append("")
        for type_, array in (("Real", "REAL_INFO"), ("Integer", "INTEGER_INFO"), ("Boolean", "BOOLEAN_INFO")):
            members = [v for v in self.variables if v.type == type_]
            lines.append(f"static const VariableInfo {array}[{max(len(members), 1)}] = {{")
            for v in members:
                start = 0.0 if v.start is None else float(v.start)
                lines.append(f'    {{"{v.name}", {_c_causality(v.causality)}, {start!r}}},')
            if not members:
                lines.append('    {"", CAUSALITY_LOCAL, 0.0},')
            lines.append("};")
        lines.append("")
        lines.append("#endif")
        return "\n".join(lines) + "\n"


def _c_causality(causality: str) -> str:
    return "CAUSALITY_" + causality.upper()


def _xml_value(type_: str, value) -> str:
    if type_ == "Boolean":
        return "true" if value else "false"
    if type_ == "Integer":
        return str(int(value))
    if not math.isfinite(float(value)):
        raise ValueError(f"non-finite start value {value!r}")
    return repr(float(value))


def _unknown(index: int, depends: list[str], indices: dict[str, int]) -> str:
    deps = " ".join(str(indices[name]) for name in depends)
    kinds = " ".join("dependent" for _ in depends)
    return f'<Unknown index="{index}" dependencies="{deps}" dependenciesKind="{kinds}"/>'
