"""Variable tables: the single source of each FMU's interface.

Each model folder holds a ``variables.py`` with one :class:`Table`. The build derives from it
both the ``modelDescription.xml`` and the C header ``variables.h`` that the shell and the
model's equations use, so a variable is declared once, with its unit and description.

Value references are assigned per type in table order (FMI 2.0 numbers Real, Integer and
Boolean variables independently), which is also the index of the variable in the instance's
arrays ``real``, ``integer`` and ``boolean``. FMI 3.0 numbers all variables in one sequence:
0 is the independent variable ``time``, then the Real (``Float64``), Integer (``Int32``) and
Boolean variables follow, each type in table order (:meth:`Table.vr3`; ``fmus/c/fmi3.c``
numbers them the same way).
"""

from __future__ import annotations

import math
import re
import uuid
from dataclasses import dataclass, field
from xml.sax.saxutils import quoteattr

CAUSALITIES = ("parameter", "input", "output")
TYPES = ("Real", "Integer", "Boolean")
#: The FMI 3.0 type of each table type.
FMI3_TYPES = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean"}


@dataclass(frozen=True)
class Variable:
    """One FMI variable of a model's table.

    Parameters
    ----------
    name : str
        Variable name, as in the Modelica twin.
    causality : str
        ``"parameter"``, ``"input"`` or ``"output"``.
    type : str
        ``"Real"``, ``"Integer"`` or ``"Boolean"``.
    start : float, int or bool, optional
        Start value, in ``unit``; required for parameters and inputs, refused for outputs.
    unit : str
        SI unit, written as the tables do (``"m/s2"``, ``"N.m.s2"``, ``"T/Hz0.5"``).
    description : str
        One line, with the frame for vectors (NED {I} or FRD {B}).
    min, max : float, optional
        Bounds declared in the model description.
    variability : str, optional
        FMI variability; by default ``fixed`` for parameters, ``continuous`` for Real
        variables and ``discrete`` for the others.
    depends : tuple of str, "all" or None
        For outputs: None means the output depends on no input (a function of the state
        only), ``"all"`` on every input, a tuple names the inputs it depends on directly
        (direct feedthrough).
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
        """The FMI 2.0 variability attribute of the variable."""
        if self.variability:
            return self.variability
        if self.causality == "parameter":
            return "fixed"
        return "continuous" if self.type == "Real" else "discrete"


def Real(name, causality, start=None, unit="", description="", **kw) -> Variable:
    """A Real :class:`Variable`.

    Parameters
    ----------
    name, causality, start, unit, description
        As for :class:`Variable`.
    **kw
        Other :class:`Variable` fields (``min``, ``max``, ``depends``, ...).
    """
    return Variable(name, causality, "Real", start, unit, description, **kw)


def Integer(name, causality, start=None, description="", **kw) -> Variable:
    """An Integer :class:`Variable` (no unit).

    Parameters
    ----------
    name, causality, start, description
        As for :class:`Variable`.
    **kw
        Other :class:`Variable` fields.
    """
    return Variable(name, causality, "Integer", start, "", description, **kw)


def Boolean(name, causality, start=None, description="", **kw) -> Variable:
    """A Boolean :class:`Variable` (no unit).

    Parameters
    ----------
    name, causality, start, description
        As for :class:`Variable`.
    **kw
        Other :class:`Variable` fields.
    """
    return Variable(name, causality, "Boolean", start, "", description, **kw)


@dataclass
class Table:
    """The variables of one model, and what the build derives from them.

    Parameters
    ----------
    model : str
        Model name (FMU model identifier).
    description : str
        One line for the model description.
    variables : list of Variable
        The rows; value references are given per type in this order.
    states : int
        Length of the model's continuous state vector (sizes the shell's RK4 scratch).
    extra_vectors : dict of str to tuple of str
        Vectors beyond those the names imply (see :meth:`vectors`).
    arrays : dict of str to str
        Real vectors the FMI 3.0 FMU declares as one array variable (``IMU.acc``), with the
        array's description; FMI 2.0 keeps their scalar members.
    """

    model: str
    description: str
    variables: list[Variable]
    states: int = 0
    # Vectors beyond those the names imply (see :meth:`vectors`): name -> member names in order,
    # e.g. the field of each motor, ``b_d1_x ... b_d4_z``, as one 12-vector.
    extra_vectors: dict[str, tuple[str, ...]] = field(default_factory=dict)
    arrays: dict[str, str] = field(default_factory=dict)
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

    def vectors(self) -> dict[str, list[Variable]]:
        """The table's vectors, by name, members in order.

        Variables whose names differ only by a final component, ``x y z`` or a number, with an
        optional underscore before it (``acc_x acc_y acc_z``, ``omega_r1 ... omega_r4``,
        ``q0 ... q3``, ``R_reel_11 ... R_reel_33``), form the vector named by the common stem
        (``acc``, ``omega_r``, ``q``, ``R_reel``); plus :attr:`extra_vectors`.

        Raises
        ------
        ValueError
            A vector's members are not consecutive rows of one type in component order (the C
            code addresses them as one array).
        """
        by_name = {v.name: v for v in self.variables}
        groups: dict[tuple[str, str], list[Variable]] = {}
        for v in self.variables:
            match = _MEMBER.fullmatch(v.name)
            if match and match.group(1):
                groups.setdefault((match.group(1), v.type), []).append(v)
        found = {stem: members for (stem, _), members in groups.items() if len(members) > 1}
        for name, members in self.extra_vectors.items():
            unknown = [n for n in members if n not in by_name]
            if unknown:
                raise ValueError(f"{self.model}: vector {name} names unknown variables {unknown}")
            found[name] = [by_name[n] for n in members]
        for name, members in found.items():
            self._check_vector(name, members, name in self.extra_vectors)
        return found

    def _check_vector(self, name: str, members: list[Variable], declared: bool):
        names = [v.name for v in members]
        if len({v.type for v in members}) > 1:
            raise ValueError(f"{self.model}: vector {name} mixes types: {names}")
        if not declared:
            keys = [_component_key(_MEMBER.fullmatch(n).group(3)) for n in names]
            if keys != sorted(keys):
                raise ValueError(f"{self.model}: the members of vector {name} are out of order in the table: "
                                 f"{', '.join(names)}. Write its rows in component order.")
        refs = [self.vr[n] for n in names]
        for previous, present, n in zip(refs, refs[1:], names[1:], strict=False):
            if present != previous + 1:
                raise ValueError(
                    f"{self.model}: the members of vector {name} ({', '.join(names)}) must be consecutive "
                    f"rows of the variable table, since the C code addresses them as one array; {n} has "
                    f"value reference {present}, not {previous + 1}. Move its rows together.")

    def array_members(self) -> dict[str, list[Variable]]:
        """The members of each FMI 3.0 array (:attr:`arrays`), in order.

        Raises
        ------
        ValueError
            An array that is not a Real vector of the table, or whose members differ in causality,
            unit or direct dependencies (one variable carries them for all).
        """
        vectors = self.vectors()
        found = {}
        for name in self.arrays:
            members = vectors.get(name)
            if not members or members[0].type != "Real":
                raise ValueError(f"{self.model}: array {name} is not a Real vector of the table")
            if len({(v.causality, v.unit, v.depends, v.variability) for v in members}) > 1:
                raise ValueError(f"{self.model}: the members of array {name} differ in causality, unit, "
                                 "dependencies or variability")
            found[name] = members
        return found

    def vr3(self, name: str) -> int:
        """The FMI 3.0 value reference of variable ``name``.

        Parameters
        ----------
        name : str
            A variable of the table, or ``"time"`` (the independent variable, 0).

        Returns
        -------
        int
            1 + its FMI 2.0 value reference, plus the count of the types before its own (Real,
            then Integer, then Boolean).
        """
        if name == "time":
            return 0
        type_ = next(v.type for v in self.variables if v.name == name)
        before = sum(self.counts[t] for t in TYPES[:TYPES.index(type_)])
        return 1 + before + self.vr[name]

    def of(self, causality: str, type_: str | None = None) -> list[Variable]:
        """The variables of one causality (and type).

        Parameters
        ----------
        causality : str
            ``"parameter"``, ``"input"`` or ``"output"``.
        type_ : str, optional
            ``"Real"``, ``"Integer"`` or ``"Boolean"``; any by default.

        Returns
        -------
        list of Variable
            In table order.
        """
        return [
            v for v in self.variables
            if v.causality == causality and (type_ is None or v.type == type_)
        ]

    @property
    def guid(self) -> str:
        """The model's GUID: stable for a given interface, so a rebuild keeps it."""
        # Stable for a given interface: a rebuild with the same table keeps the GUID.
        text = "|".join(f"{v.name}:{v.causality}:{v.type}" for v in self.variables)
        return "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, f"quadcosim/{self.model}/{text}")) + "}"

    # ----------------------------------------------------------------- modelDescription.xml
    def model_description(self, source_files: list[str], fmi_version: int = 2) -> str:
        """The ``modelDescription.xml`` of the model.

        Parameters
        ----------
        source_files : list of str
            C sources listed for a source FMU (FMI 2.0; FMI 3.0 lists them in
            :meth:`build_description`).
        fmi_version : int
            2 or 3.

        Returns
        -------
        str
            The XML text, with SI base units declared for each unit definition.
        """
        if fmi_version == 3:
            return self._model_description_fmi3()
        if fmi_version != 2:
            raise ValueError(f"FMI version {fmi_version!r}: the build writes FMI 2 and 3")
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
            '  generationTool="quadcosim quadcosim.fmus.build"',
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
            lines += [f"    {_unit_definition(u)}" for u in units]
            lines.append("  </UnitDefinitions>")
        lines.append('  <DefaultExperiment startTime="0" stopTime="2" stepSize="0.001"/>')
        lines.append("  <ModelVariables>")
        for v in self.variables:
            lines.append(f"    <!-- {index[v.name]} -->")
            lines += self._scalar_variable(v)
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

    def _model_description_fmi3(self) -> str:
        inputs = [v.name for v in self.variables if v.causality == "input"]
        units = sorted({v.unit for v in self.variables if v.unit} | {"s"})
        lines = [
            '<?xml version="1.0" encoding="UTF-8"?>',
            "<fmiModelDescription",
            '  fmiVersion="3.0"',
            f'  modelName="{self.model}"',
            f'  instantiationToken="{self.guid}"',
            f"  description={quoteattr(self.description)}",
            '  generationTool="quadcosim quadcosim.fmus.build"',
            '  variableNamingConvention="flat">',
            f'  <CoSimulation modelIdentifier="{self.model}" canHandleVariableCommunicationStepSize="true"'
            ' hasEventMode="false"/>',
            "  <UnitDefinitions>",
            *[f"    {_unit_definition(u)}" for u in units],
            "  </UnitDefinitions>",
            '  <DefaultExperiment startTime="0" stopTime="2" stepSize="0.001"/>',
            "  <ModelVariables>",
            '    <Float64 name="time" valueReference="0" causality="independent" variability="continuous"'
            ' description="simulation time" unit="s"/>',
        ]
        arrays = self.array_members()
        inner = {v.name for members in arrays.values() for v in members[1:]}  # carried by the first
        heads = {members[0].name: (name, len(members)) for name, members in arrays.items()}
        for v in self.variables:
            if v.name not in inner:
                lines.append(f"    {self._variable_fmi3(v, *heads.get(v.name, (None, 0)))}")
        lines.append("  </ModelVariables>")
        lines.append("  <ModelStructure>")
        outputs = [v for v in self.of("output") if v.name not in inner]
        for v in outputs:
            deps = [self.vr3(n) for n in self._depends(v, inputs) if n not in inner]
            lines.append(f'    <Output valueReference="{self.vr3(v.name)}" '
                         f'dependencies="{" ".join(map(str, deps))}" '
                         f'dependenciesKind="{" ".join("dependent" for _ in deps)}"/>')
        for v in outputs:
            lines.append(f'    <InitialUnknown valueReference="{self.vr3(v.name)}"/>')
        lines.append("  </ModelStructure>")
        lines.append("</fmiModelDescription>")
        return "\n".join(lines) + "\n"

    def _variable_fmi3(self, v: Variable, array: str | None = None, length: int = 0) -> str:
        attrs = [
            f'name="{array or v.name}"',
            f'valueReference="{self.vr3(v.name)}"',
            f'causality="{v.causality}"',
            f'variability="{v.fmi_variability}"',
        ]
        if v.causality == "parameter":
            attrs.append('initial="exact"')
        description = self.arrays[array] if array else v.description
        if description:
            attrs.append(f"description={quoteattr(description)}")
        if v.start is not None:
            members = self.array_members()[array] if array else [v]
            attrs.append(f'start="{" ".join(_xml_value(m.type, m.start) for m in members)}"')
        if v.unit:
            attrs.append(f'unit="{v.unit}"')
        if v.min is not None:
            attrs.append(f'min="{v.min!r}"')
        if v.max is not None:
            attrs.append(f'max="{v.max!r}"')
        if array:
            return f'<{FMI3_TYPES[v.type]} {" ".join(attrs)}><Dimension start="{length}"/></{FMI3_TYPES[v.type]}>'
        return f"<{FMI3_TYPES[v.type]} {' '.join(attrs)}/>"

    def build_description(self, source_files: list[str]) -> str:
        """The FMI 3.0 ``sources/buildDescription.xml``: how to compile the model from its sources.

        Parameters
        ----------
        source_files : list of str
            The C files to compile (C99), in ``sources/`` beside their headers.

        Returns
        -------
        str
            The XML text.
        """
        return "\n".join([
            '<?xml version="1.0" encoding="UTF-8"?>',
            '<fmiBuildDescription fmiVersion="3.0">',
            f'  <BuildConfiguration modelIdentifier="{self.model}">',
            '    <SourceFileSet language="C99">',
            *[f'      <SourceFile name="{name}"/>' for name in source_files],
            "    </SourceFileSet>",
            "  </BuildConfiguration>",
            "</fmiBuildDescription>",
        ]) + "\n"

    def _scalar_variable(self, v: Variable) -> list[str]:
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
        return [f"    <ScalarVariable {' '.join(attrs)}>",
                f"      <{v.type} {' '.join(type_attrs)}/>".replace(" />", "/>"),
                "    </ScalarVariable>"]

    @staticmethod
    def _depends(v: Variable, inputs: list[str]) -> list[str]:
        if v.depends is None:
            return []
        if v.depends == "all":
            return inputs
        return list(v.depends)

    # ----------------------------------------------------------------- variables.h
    def c_header(self, fmi_version: int = 2) -> str:
        """The ``variables.h`` the shell and the model's equations include.

        Parameters
        ----------
        fmi_version : int
            2, or 3: the header then defines ``FMI_VERSION`` as 3 for ``shell.h``.

        Returns
        -------
        str
            Value reference constants (``VR_name``), vector constants (``VEC_name``,
            ``LEN_name``) and the variable information arrays.
        """
        lines = [
            f"/* Generated from fmus/{self.model}/variables.py by quadcosim.fmus.build: do not edit. */",
            "#ifndef VARIABLES_H",
            "#define VARIABLES_H",
            "",
            *(["#define FMI_VERSION 3"] if fmi_version == 3 else []),
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
        prefixes = {"Real": "VR_", "Integer": "VI_", "Boolean": "VB_"}
        for type_, prefix in prefixes.items():
            members = [v for v in self.variables if v.type == type_]
            if members:
                lines.append("enum {")
                lines += [f"    {prefix}{v.name} = {self.vr[v.name]}," for v in members]
                lines.append("};")
        vectors = self.vectors()
        if vectors:
            lines += ["", "/* Vectors: consecutive variables of one type, checked by the build. VEC_v is the",
                      " * value reference of the first member of vector v, LEN_v its length; a model reads",
                      " * member k of a Real vector as REAL_VECTOR(m, v)[k]. */", "enum {"]
            for name, members in vectors.items():
                prefix = prefixes[members[0].type]
                lines.append(f"    VEC_{name} = {prefix}{members[0].name}, LEN_{name} = {len(members)},")
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
        if fmi_version == 3:
            arrays = self.array_members()
            lines += ["/* FMI 3.0 arrays: a Real vector declared as one variable, by the index of its first member",
                      " * and its length; the later members have no value reference of their own. */",
                      f"#define N_ARRAYS {len(arrays)}",
                      f"static const int ARRAY_FIRST[{max(len(arrays), 1)}] = "
                      f"{{{', '.join(f'VEC_{n}' for n in arrays) or '0'}}};",
                      f"static const int ARRAY_LENGTH[{max(len(arrays), 1)}] = "
                      f"{{{', '.join(f'LEN_{n}' for n in arrays) or '0'}}};"]
        lines.append("")
        lines.append("#endif")
        return "\n".join(lines) + "\n"


# A vector member's name: a stem, an optional underscore, a component (x, y, z or a number).
_MEMBER = re.compile(r"(.*?)(_?)([xyz]|\d+)")


def _component_key(component: str) -> tuple[int, int]:
    return (0, "xyz".index(component)) if component in "xyz" else (1, int(component))


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


# SI base units of the symbols the tables use (FMI 2.0 BaseUnit exponents: kg, m, s, A, K, mol,
# cd, rad). A unit is written as symbols with optional exponents joined by "." and "/", e.g.
# "N.m.s2", "m/s2", "T/A"; each "/" divides by the factor that follows it.
BASE_SYMBOLS = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")
SYMBOLS: dict[str, dict[str, int]] = {
    "1": {}, "kg": {"kg": 1}, "m": {"m": 1}, "s": {"s": 1}, "A": {"A": 1}, "K": {"K": 1},
    "rad": {"rad": 1}, "Hz": {"s": -1},
    "N": {"kg": 1, "m": 1, "s": -2},
    "V": {"kg": 1, "m": 2, "s": -3, "A": -1},
    "Ohm": {"kg": 1, "m": 2, "s": -3, "A": -2},
    "H": {"kg": 1, "m": 2, "s": -2, "A": -2},
    "T": {"kg": 1, "s": -2, "A": -1},
}


def base_unit(unit: str) -> dict[str, int] | None:
    """Exponents of the SI base units of ``unit`` (``"T"`` -> ``{"kg": 1, "s": -2, "A": -1}``).

    Parameters
    ----------
    unit : str
        A unit as the variable tables write it.

    Returns
    -------
    dict of str to int, or None
        Non-zero exponents by base symbol; None when an exponent is not an integer (the noise
        densities per square root of hertz), which FMI 2.0's ``BaseUnit`` cannot express.

    Raises
    ------
    ValueError
        A symbol that is not in :data:`SYMBOLS`.
    """
    exponents: dict[str, float] = {}
    for k, part in enumerate(unit.split("/")):
        for factor in re.split(r"\.(?=[A-Za-z])", part):  # "Hz0.5": the dot of a number stays
            match = re.fullmatch(r"([A-Za-z]+|1)(\d+(?:\.\d+)?)?", factor)
            if not match or match.group(1) not in SYMBOLS:
                raise ValueError(f"unit {unit!r}: unknown symbol {factor!r}; known: {', '.join(SYMBOLS)}")
            power = float(match.group(2) or 1) * (-1 if k else 1)
            for base, exponent in SYMBOLS[match.group(1)].items():
                exponents[base] = exponents.get(base, 0) + exponent * power
    if any(e != int(e) for e in exponents.values()):
        return None
    return {b: int(exponents[b]) for b in BASE_SYMBOLS if exponents.get(b)}


def _unit_definition(unit: str) -> str:
    base = base_unit(unit)
    if base is None:  # a fractional power of a second: the unit is named, not converted
        return f'<Unit name="{unit}"/>'
    attrs = "".join(f' {b}="{e}"' for b, e in base.items())
    return f'<Unit name="{unit}"><BaseUnit{attrs}/></Unit>'
