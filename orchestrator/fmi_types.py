"""FMI variable types on the master's bus, and the calls an FMU block makes in the loop.

The bus holds every signal as a float64. An FMU's numeric variables are its block's signals,
whatever their FMI type: FMI 2.0 Real, Integer, Boolean and Enumeration; FMI 3.0 Float32,
Float64, Int8 to UInt64, Boolean and Enumeration. An integer or a Boolean is exact on the bus
(an integer above 2^53 in magnitude, of an Int64 or UInt64, is not); its type is kept
(:func:`dtypes`), for the record and its files. An FMI 3.0 array of shape ``(n,)`` is the vector
signal ``NAME`` with the components ``NAME_1`` to ``NAME_n``, one of shape ``(n, m)``
``NAME_11`` to ``NAME_nm`` (row by row; ``NAME_1_1`` when a dimension exceeds 9).

A value set into an integer input is rounded to the nearest integer and held in the type's
range; a Boolean input is true when its value is not zero. String and Binary variables are not
signals: their values are recorded once, as parameters are (:meth:`quadcosim.orchestrator.fmu.FMUInstance.texts`).

Every FMI call of the loop is a :class:`CEntry`: a C function of one of three signatures, that of
``fmi2SetReal`` (set), ``fmi2GetReal`` (get) or ``fmi2DoStep`` (step), and its first argument.
For an FMI 2.0 FMU's Real variables in consecutive bus slots it is the FMU's own function, and
costs nothing more; every other call goes through ``orchestrator/c/typed.c``, which converts
between the bus and the FMU's types in preallocated buffers.
"""

from __future__ import annotations

import ctypes
from typing import NamedTuple, Protocol

import numpy as np

#: FMI type -> (type code of ``typed.c``, NumPy type of its values, suffix of its setter and getter).
FMI2_TYPES = {"Real": (0, np.float64, "Real"), "Integer": (11, np.int32, "Integer"),
              "Enumeration": (11, np.int32, "Integer"), "Boolean": (12, np.bool_, "Boolean")}
FMI3_TYPES = {"Float64": (0, np.float64, "Float64"), "Float32": (1, np.float32, "Float32"),
              "Int8": (2, np.int8, "Int8"), "UInt8": (3, np.uint8, "UInt8"), "Int16": (4, np.int16, "Int16"),
              "UInt16": (5, np.uint16, "UInt16"), "Int32": (6, np.int32, "Int32"), "UInt32": (7, np.uint32, "UInt32"),
              "Int64": (8, np.int64, "Int64"), "UInt64": (9, np.uint64, "UInt64"), "Boolean": (10, np.bool_, "Boolean"),
              "Enumeration": (8, np.int64, "Int64")}
#: The integer types of FMI 2.0 and 3.0 (an enumeration is an integer).
INTEGER_TYPES = {"Integer", "Enumeration", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64"}
#: Variable types that are not signals: recorded once as text (String, Binary), or refused (Clock).
TEXT_TYPES = ("String", "Binary")
SCRATCH = {0: ctypes.c_double, 1: ctypes.c_float, 2: ctypes.c_int8, 3: ctypes.c_uint8, 4: ctypes.c_int16,
           5: ctypes.c_uint16, 6: ctypes.c_int32, 7: ctypes.c_uint32, 8: ctypes.c_int64, 9: ctypes.c_uint64,
           10: ctypes.c_bool, 11: ctypes.c_int, 12: ctypes.c_int}


def types_of(fmi3: bool) -> dict:
    """The signal types of FMI 3.0 (``fmi3``) or FMI 2.0, as :data:`FMI3_TYPES` and :data:`FMI2_TYPES`."""
    return FMI3_TYPES if fmi3 else FMI2_TYPES


class Signal(NamedTuple):
    """One scalar signal of an FMU: a scalar variable, or one element of an array variable.

    Parameters
    ----------
    name : str
        Signal name (``"counter"``, ``"acc_1"``).
    variable : fmpy.model_description.ModelVariable
        The variable it belongs to.
    index : int
        Its element in the variable, row by row (0 for a scalar).
    """

    name: str
    variable: object
    index: int


def element_names(name: str, shape: tuple) -> list[str]:
    """Signal names of the elements of an array variable ``name`` of ``shape``, row by row."""
    if not shape:
        return [name]
    separator = "" if len(shape) == 2 and max(shape) <= 9 else "_"
    indices = np.indices(shape).reshape(len(shape), -1).T + 1
    return [f"{name}_" + separator.join(str(i) for i in index) for index in indices]


def is_fmi3(description) -> bool:
    """Whether an fmpy model description is of FMI 3.0."""
    return str(description.fmiVersion).startswith("3.")


def signals(description, causality: str) -> list[Signal]:
    """The scalar signals of the numeric variables of ``causality``, in the order of the model description.

    Parameters
    ----------
    description : fmpy.model_description.ModelDescription
    causality : {"input", "output"}

    Returns
    -------
    list of Signal
    """
    kinds = types_of(is_fmi3(description))
    found = []
    for variable in description.modelVariables:
        if variable.causality == causality and variable.type in kinds:
            names = element_names(variable.name, tuple(variable.shape or ()))
            found.extend(Signal(name, variable, k) for k, name in enumerate(names))
    return found


def dtypes(description, names) -> dict[str, str]:
    """NumPy type names of the signals of an FMU that are not float64.

    Parameters
    ----------
    description : fmpy.model_description.ModelDescription
        The FMU's model description.
    names : sequence of str
        Signal names of its inputs and outputs.

    Returns
    -------
    dict of str to str
        ``{"counter": "int32"}``; a float64 signal is left out.
    """
    kinds = types_of(is_fmi3(description))
    by_name = {s.name: s for causality in ("input", "output") for s in signals(description, causality)}
    found = {}
    for name in names:
        dtype = np.dtype(kinds[by_name[name].variable.type][1])
        if dtype != np.float64:
            found[name] = dtype.name
    return found


def is_parameter(variable) -> bool:
    """Whether a variable is set by name before a run: a parameter, or a String or Binary input
    (not a signal, so set once, at initialization)."""
    return variable.causality == "parameter" or (variable.causality == "input" and variable.type in TEXT_TYPES)


def unit(variable) -> str:
    """The unit of a variable, its own or its declared type's; ``""`` if none."""
    return variable.unit or getattr(variable.declaredType, "unit", None) or ""


class CEntry(NamedTuple):
    """One FMI call of the loop, as the call runner (``orchestrator/c/calls.c``) makes it.

    Parameters
    ----------
    function : int
        Address of a C function of the signature of ``fmi2SetReal``, ``fmi2GetReal`` or
        ``fmi2DoStep``.
    component : int
        Its first argument (the FMU instance, or the context of a typed call).
    vr : int
        Address of the value references (uint32), or 0.
    n : int
        Their count.
    values : int
        Address of the first float64 value on the bus, or 0.
    label : str
        The FMI functions it calls, for messages (``"fmi2SetReal"``).
    keep : object
        What must stay alive while the address is called.
    """

    function: int
    component: int
    vr: int
    n: int
    values: int
    label: str
    keep: object = None


class Stepping(Protocol):
    """What the master needs of an FMU instance (:class:`quadcosim.orchestrator.fmu.FMUInstance` for FMI 2.0,
    :class:`quadcosim.orchestrator.fmu.FMU3Instance` for FMI 3.0, or a stand-in that runs one elsewhere).

    Every value crosses as a float64. The loop makes only the C calls that :meth:`setter`,
    :meth:`getter` and :meth:`stepper` return, once per run; the rest is set-up.
    """

    name: str
    log: object  # quadcosim.orchestrator.fmu_errors.FMULog
    inputs: list
    outputs: list

    def get(self, names) -> np.ndarray:
        """Signals ``names``, as float64."""

    def set(self, names, values) -> None:
        """Set inputs ``names`` from float64 ``values``."""

    def step(self, t: float, h: float) -> None:
        """One communication step from ``t`` by ``h`` (s)."""

    def setter(self, names, addresses) -> list[CEntry]:
        """C calls that set inputs ``names`` from the float64 at each of ``addresses``."""

    def getter(self, names, addresses) -> list[CEntry]:
        """C calls that write outputs ``names`` to the float64 at each of ``addresses``."""

    def stepper(self) -> CEntry:
        """The C call of one communication step, ``(component, t, h, 1)``."""

    def texts(self) -> dict[str, str]:
        """String and Binary values, by name."""

    def terminated(self) -> bool:
        """Whether the FMU asked to end the simulation in its last step."""

    def reset(self, parameters=None, name=None, start_time: float = 0.0) -> None:
        """Back to a fresh instance's state: ``parameters`` set, ``name`` for messages,
        initialized at ``start_time`` (s)."""

    def close(self) -> None:
        """Terminate and free."""


class _Group(ctypes.Structure):
    _fields_ = [("function", ctypes.c_void_p), ("instance", ctypes.c_void_p), ("type", ctypes.c_int),
                ("fmi3", ctypes.c_int), ("vr", ctypes.c_void_p), ("nvr", ctypes.c_size_t),
                ("nvalues", ctypes.c_size_t), ("where", ctypes.c_void_p), ("scratch", ctypes.c_void_p)]


class _Typed(ctypes.Structure):
    _fields_ = [("groups", ctypes.c_void_p), ("count", ctypes.c_long), ("failed", ctypes.c_long)]


class Step3(ctypes.Structure):
    """The context of an FMI 3.0 ``fmi3DoStep`` call (``step3`` in ``typed.c``): what it returned."""

    _fields_ = [("function", ctypes.c_void_p), ("instance", ctypes.c_void_p), ("terminated", ctypes.c_int),
                ("early", ctypes.c_int), ("last", ctypes.c_double)]


_library = None


def typed_path(build: bool = False):
    """The compiled ``orchestrator/c/typed.c``, beside the call runner
    (:func:`quadcosim.orchestrator.calls.runner_dir`): compiled when missing or older than its source, or
    when ``build``.

    Returns
    -------
    pathlib.Path
    """
    from pathlib import Path

    from quadcosim.orchestrator.calls import compile_shared, runner_dir

    source = Path(__file__).resolve().parent / "c" / "typed.c"
    library = runner_dir() / "libquadcosim_typed.so"
    if build or not library.is_file() or library.stat().st_mtime < source.stat().st_mtime:
        compile_shared(source, library)
    return library


def typed_library() -> ctypes.CDLL:
    """The typed calls' library (:func:`typed_path`), loaded once per process."""
    global _library
    if _library is None:
        _library = ctypes.CDLL(str(typed_path()))
    return _library


def address(function) -> int:
    """The address of a ctypes function."""
    return ctypes.cast(function, ctypes.c_void_p).value


def typed_entry(function_of, component: int, fmi3: bool, pairs: list[tuple[Signal, int]], direction: str) -> CEntry:
    """A typed call: the signals of ``pairs`` set from, or got into, their bus addresses.

    Parameters
    ----------
    function_of : callable
        FMI function name (``"fmi3SetInt32"``) to its ctypes function.
    component : int
        The FMU instance.
    fmi3 : bool
        The FMU is of FMI 3.0.
    pairs : list of (Signal, int)
        Each signal and the address of its float64 on the bus. An FMI 3.0 array is set and got
        whole: every element of an array in ``pairs`` must be there.
    direction : {"Set", "Get"}

    Returns
    -------
    CEntry
    """
    kinds = types_of(fmi3)
    by_variable: dict[int, dict] = {}
    for signal, where in pairs:
        by_variable.setdefault(id(signal.variable), {"variable": signal.variable})[signal.index] = where
    groups_of: dict[int, list] = {}  # type code -> [(variable, [addresses])]
    for entry in by_variable.values():
        variable = entry.pop("variable")
        size = int(np.prod(variable.shape or ())) if fmi3 else 1
        if sorted(entry) != list(range(size)):
            raise ValueError(f"{variable.name}: an FMI 3.0 array is set and read whole; {len(entry)} of its "
                             f"{size} elements were given")
        groups_of.setdefault(kinds[variable.type][0], []).append((variable, [entry[k] for k in range(size)]))
    groups, keep, labels = [], [], []
    for code, members in groups_of.items():
        name = f"fmi{3 if fmi3 else 2}{direction}{next(k[2] for k in kinds.values() if k[0] == code)}"
        refs = (ctypes.c_uint32 * len(members))(*[v.valueReference for v, _ in members])
        where = [a for _, addresses in members for a in addresses]
        addresses = (ctypes.c_void_p * len(where))(*where)
        scratch = (SCRATCH[code] * len(where))()
        groups.append(_Group(address(function_of(name)), component, code, int(fmi3), ctypes.addressof(refs),
                             len(members), len(where), ctypes.addressof(addresses), ctypes.addressof(scratch)))
        keep += [refs, addresses, scratch]
        labels.append(name)
    array = (_Group * len(groups))(*groups)
    context = _Typed(ctypes.addressof(array), len(groups), -1)
    function = typed_library()["typed_set" if direction == "Set" else "typed_get"]
    return CEntry(address(function), ctypes.addressof(context), 0, 0, 0, ", ".join(labels),
                  _TypedKeep(array, context, keep, function, labels))


class _TypedKeep(NamedTuple):
    """What a typed call keeps alive, and the FMI function of each of its groups."""

    array: object
    context: _Typed
    buffers: list
    function: object
    labels: list

    def failed_function(self) -> str:
        """The FMI function of the group the call failed in (``"fmi3SetInt8"``), or all of them."""
        failed = self.context.failed
        return self.labels[failed] if 0 <= failed < len(self.labels) else ", ".join(self.labels)


def step3_entry(do_step, component: int) -> CEntry:
    """The call of ``fmi3DoStep`` through ``step3`` (``typed.c``), its context in ``keep[0]``.

    Parameters
    ----------
    do_step : ctypes function
        The FMU's ``fmi3DoStep``.
    component : int
        The FMU instance.

    Returns
    -------
    CEntry
    """
    context = Step3(address(do_step), component, 0, 0, 0.0)
    function = typed_library()["step3"]
    return CEntry(address(function), ctypes.addressof(context), 0, 0, 0, "fmi3DoStep", (context, function))
