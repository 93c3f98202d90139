"""Loading and stepping one Co-Simulation FMU, FMI 2.0 or 3.0, through fmpy.

:class:`FMUInstance` does the set-up once (extraction, instantiation, parameters,
initialization) with clear errors. It is an FMI 2.0 instance, or, for an FMI 3.0 file, an
:class:`FMU3Instance`; both keep one protocol, by which a block and its
master (or a worker process hosting the instance) step it:

- by signal name, for set-up and tests: :meth:`FMUInstance.set`, :meth:`FMUInstance.get`,
  :meth:`FMUInstance.step`, all with float64 values;
- in the loop: :meth:`FMUInstance.setter`, :meth:`FMUInstance.getter` and
  :meth:`FMUInstance.stepper` give, once, C calls (:class:`quadcosim.orchestrator.fmi_types.CEntry`) that
  read and write float64 values at fixed addresses (the bus, or a shared buffer) with no name
  look-up and no allocation per step;
- :meth:`FMUInstance.reset`, :meth:`FMUInstance.close`, and :attr:`FMUInstance.log`.

The signals (:attr:`FMUInstance.inputs`, :attr:`FMUInstance.outputs`) are the numeric variables
of every FMI type, an FMI 3.0 array as one signal per element (:mod:`quadcosim.orchestrator.fmi_types`).
"""

from __future__ import annotations

import atexit
import ctypes
import difflib
import itertools
import math
import shutil
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.fmi3 import FMU3Slave
from fmpy.logging import addLoggerProxy
from quadcosim.fmus import fmu_path
from quadcosim.orchestrator.fmi_types import (
    INTEGER_TYPES,
    TEXT_TYPES,
    CEntry,
    address,
    is_parameter,
    signals,
    step3_entry,
    typed_entry,
    types_of,
)
from quadcosim.orchestrator.fmu_errors import (  # noqa: F401 (public here too)
    STATUS,
    FMUError,
    FMULog,
    ParameterRefused,
    failed,
    keep,
    status_name,
)

_extracted: dict[tuple[str, float], str] = {}
_logs: dict[bytes, FMULog] = {}  # instance name -> its log
_instances = itertools.count(1)


def _on_log(env, instance, status, category, message):
    log = _logs.get(instance)
    if log is not None:  # an FMULog, or a plain deque of a test's raw instance
        keep(log, status, message)


# fmpy's native proxy formats the FMU's variadic messages; it keeps one Python logger for the
# whole process, so there is one callback structure and messages are routed by instance name.
_CALLBACKS = fmi2CallbackFunctions()
_LOGGER = fmi2CallbackLoggerTYPE(_on_log)
_CALLBACKS.logger = _LOGGER
_CALLBACKS.allocateMemory = fmi2CallbackAllocateMemoryTYPE(ctypes.CDLL(None).calloc)
_CALLBACKS.freeMemory = fmi2CallbackFreeMemoryTYPE(ctypes.CDLL(None).free)
addLoggerProxy(ctypes.byref(_CALLBACKS))


_descriptions: dict[tuple, object] = {}


def is_fmu_file(model) -> bool:
    """Whether ``model`` names an FMU file (``"my_motor.fmu"``, a path) rather than a built model."""
    return str(model).lower().endswith(".fmu")


def fmu_file(model) -> Path:
    """The FMU file of ``model``: a built model by name (:func:`quadcosim.fmus.fmu_path`), or a path to any
    FMI 2.0 or 3.0 Co-Simulation FMU, made absolute.

    Parameters
    ----------
    model : str or pathlib.Path
        ``"IMU"``, or ``"my_motor.fmu"``, ``"models/motor.fmu"``.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    FileNotFoundError
        No file at the path given (the message names it, from the current folder).
    ValueError
        The file is not an FMI 2.0 or 3.0 FMU for Co-Simulation, or it has clocks (the message
        says what it is).
    """
    if not is_fmu_file(model):
        return fmu_path(model)
    path = Path(model).expanduser().absolute()
    if not path.is_file():
        raise FileNotFoundError(f"FMU file {model} not found (looked at {path}); give the path of an .fmu file, or "
                                "a built model's name (IMU, Quadrotor, MotorMagnetics)")
    from quadcosim.orchestrator.fmu_checks import FMURefused, check_archive, check_file

    try:
        check_archive(path)  # before the description is read: no entry of a zip bomb is expanded
        description = model_description(path)
    except FMURefused:
        raise
    except Exception as error:  # fmpy raises several kinds on a file that is not an FMU
        raise ValueError(f"{model} is not a readable FMU: {error}") from None
    version = str(description.fmiVersion)
    if not version.startswith(("2.", "3.")):
        raise ValueError(f"{model} is an FMI {version} FMU; the master runs FMI 2.0 and 3.0 FMUs (export "
                         "for FMI 3.0 or 2.0 Co-Simulation)")
    if description.coSimulation is None:
        raise ValueError(f"{model} is an FMI {version[0]}.0 Model Exchange FMU only; the master runs Co-Simulation "
                         f"FMUs (export for FMI {version[0]}.0 Co-Simulation, with its own solver)")
    clocks = [v.name for v in description.modelVariables if v.type == "Clock"]
    if clocks:
        raise ValueError(f"{model} has clocks ({', '.join(clocks)}): the master runs FMI 3.0 Co-Simulation without "
                         "event mode, which clocks need. Export the FMU without clocks (its clocked partitions "
                         "sampled at a fixed rate of its own)")
    check_file(path, description)
    return path


def model_description(path):
    """fmpy's model description of the FMU file ``path``, parsed once per version of the file
    (its path, modification time and size): a sweep's members share it rather than each
    parsing the XML again. Callers read it and never change it.

    Parameters
    ----------
    path : str or pathlib.Path
        An ``.fmu`` file.

    Returns
    -------
    fmpy.model_description.ModelDescription
    """
    stat = Path(path).stat()
    key = (str(path), stat.st_mtime_ns, stat.st_size)
    description = _descriptions.get(key)
    if description is None:
        description = _descriptions[key] = read_model_description(str(path))
    return description


def _unzip(path: Path) -> str:
    key = (str(path), path.stat().st_mtime)
    if key not in _extracted:
        _extracted[key] = extract(str(path))
    return _extracted[key]


@atexit.register
def _cleanup():
    for directory in _extracted.values():
        shutil.rmtree(directory, ignore_errors=True)


def nearest(name: str, candidates, n: int = 3) -> str:
    """``"did you mean a, b?"`` for the candidates closest to ``name`` (in any case, when none is close as
    written: ``Imu`` finds ``IMU``)."""
    candidates = list(candidates)
    close = difflib.get_close_matches(name, candidates, n=n, cutoff=0.5)
    if not close:
        folded = {str(c).lower(): c for c in candidates}
        close = [folded[c] for c in difflib.get_close_matches(name.lower(), list(folded), n=n, cutoff=0.5)]
    return f" Did you mean {', '.join(close)}?" if close else ""


_SET_OR_GET = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p)


def fmi_version(model) -> int:
    """2 or 3: the FMI version of ``model`` (a built model's name or an FMU file)."""
    return 3 if str(model_description(fmu_file(model)).fmiVersion).startswith("3.") else 2


class FMUInstance:
    """One instantiated and initialized FMU: FMI 2.0 here, and an
    :class:`FMU3Instance` (made by this class) for an FMI 3.0 file.

    Parameters
    ----------
    model : str
        Name of a built FMU (``"Quadrotor"``, ``"MotorMagnetics"``, ``"IMU"``), found by
        :func:`quadcosim.fmus.fmu_path`, or a path to an ``.fmu`` file.
    parameters : dict, optional
        Overrides of parameter start values, by variable name.
    name : str, optional
        Instance (block) name used in messages; defaults to the model name.
    start_time : float
        Start time (s).

    Attributes
    ----------
    inputs, outputs : list of str
        The signals: numeric variables of every FMI type, an FMI 3.0 array one signal per element.
    signal : dict
        Signal name to its :class:`quadcosim.orchestrator.fmi_types.Signal`.
    """

    fmi3 = False

    def __new__(cls, model, *args, **kwargs):
        if cls is FMUInstance and fmi_version(model) == 3:
            cls = FMU3Instance
        return super().__new__(cls)

    def __init__(self, model: str, parameters: dict | None = None, name: str | None = None,
                 start_time: float = 0.0):
        path = fmu_file(model)
        self.path = path
        self.name = name or path.stem
        self.time = start_time
        self.log = FMULog()
        description = model_description(path)
        self.description = description
        self.variables = {v.name: v for v in description.modelVariables}
        self.parameters = [v.name for v in description.modelVariables if is_parameter(v)]
        self.signal = {s.name: s for causality in ("input", "output") for s in signals(description, causality)}
        self.inputs = [s.name for s in signals(description, "input")]
        self.outputs = [s.name for s in signals(description, "output")]
        self.all_real = all(v.type in ("Real", "Float64") for v in self.variables.values()
                            if v.causality in ("input", "output") and not v.shape) and not self.fmi3
        overrides = self._check_parameters(parameters or {})
        self._instance_name = f"{self.name}#{next(_instances)}"
        _logs[self._instance_name.encode()] = self.log
        self.closed = True
        self._open()
        self.closed = False
        try:
            self._initialize(overrides, start_time)
        except FMUError as error:  # a value the model refuses: refused input, the instance freed
            self.close()
            raise ParameterRefused(error, overrides, path.stem) from None
        except Exception:
            self.close()
            raise

    def _open(self):
        """Load the binary and instantiate (FMI 2.0)."""
        description = self.description
        self._slave = FMU2Slave(
            guid=description.guid,
            unzipDirectory=_unzip(self.path),
            modelIdentifier=description.coSimulation.modelIdentifier,
            instanceName=self._instance_name,
        )
        self._call(lambda: self._slave.instantiate(callbacks=_CALLBACKS), "fmi2Instantiate")
        self.component = self._slave.component
        # One set of handles for every path: fresh function objects without argtypes, called
        # with prebuilt ctypes arguments, skip ctypes' per-call conversions (0.66 against 2.2 us
        # here). fmpy's own wrappers serve only the set-up calls above and below.
        dll = self._slave.dll
        self.raw_set_real, self.raw_get_real, self.raw_do_step = (
            dll["fmi2SetReal"], dll["fmi2GetReal"], dll["fmi2DoStep"])
        for function in (self.raw_set_real, self.raw_get_real, self.raw_do_step):
            function.restype = ctypes.c_int
        self.component_arg = ctypes.c_void_p(self.component)

    def _function(self, name: str):
        """The FMU's C function ``name`` (``"fmi2SetInteger"``)."""
        return self._slave.dll[name]

    def _initialize(self, overrides: dict, start_time: float):
        self._call(lambda: self._slave.setupExperiment(startTime=start_time), "fmi2SetupExperiment")
        self._call(self._slave.enterInitializationMode, "fmi2EnterInitializationMode")
        self._set_parameters(overrides)
        self._call(self._slave.exitInitializationMode, "fmi2ExitInitializationMode")

    def _set_parameters(self, overrides: dict):
        kinds = types_of(self.fmi3)
        by_setter: dict[str, list[str]] = {}  # one call per setter, in the order given
        for name in overrides:
            kind = self.variables[name].type
            by_setter.setdefault(kinds[kind][2] if kind in kinds else kind, []).append(name)
        for suffix, names in by_setter.items():
            setter = getattr(self._slave, f"set{suffix}")
            refs = [self.variables[name].valueReference for name in names]
            values = [overrides[name] for name in names]
            label = f"fmi{3 if self.fmi3 else 2}Set{suffix}({', '.join(names)})"
            self._call(lambda setter=setter, refs=refs, values=values: setter(refs, values), label)

    def reset(self, parameters: dict | None = None, name: str | None = None, start_time: float = 0.0):
        """Make this instance what a new one with these arguments would be: ``fmi2Reset`` (every
        variable back to its start value, the model's state cleared), then the set-up and
        initialization of :class:`FMUInstance`, and an empty log. The FMUs' reset reproduces a
        fresh instance bit for bit (``tests/test_fmu_reset.py``).

        Parameters
        ----------
        parameters : dict, optional
            Overrides of parameter start values, by variable name.
        name : str, optional
            Instance (block) name used in messages; the model name by default.
        start_time : float
            Start time (s).

        Raises
        ------
        FMUError
            The FMU refused the reset (:class:`ParameterRefused`: the new parameters); the
            instance is then closed.
        """
        overrides = self._check_parameters(parameters or {})
        self.name = name or self.path.stem
        self.time = start_time
        self.log.clear()
        self.log.warnings, self.log.first_warnings = 0, []
        try:
            self._call(self._slave.reset, f"fmi{3 if self.fmi3 else 2}Reset")
        except Exception:
            self.close()
            raise
        try:
            self._initialize(overrides, start_time)
        except FMUError as error:  # a value the model refuses: refused input, the instance freed
            self.close()
            raise ParameterRefused(error, overrides, self.path.stem) from None
        except Exception:
            self.close()
            raise

    # ------------------------------------------------------------------ set-up helpers
    def _call(self, function, label: str):
        from fmpy.fmi1 import FMICallException

        try:
            return function()
        except FMICallException as error:
            raise FMUError(self.name, label, error.status, self.time, list(self.log)) from None
        except Exception as error:
            if "Failed to instantiate" in str(error):
                raise FMUError(self.name, label, 3, self.time, list(self.log)) from None
            raise

    def _check_parameters(self, parameters: dict) -> dict:
        checked = {}
        for name, value in parameters.items():
            variable = self.variables.get(name)
            if variable is None or not is_parameter(variable):
                raise ValueError(
                    f"{self.name} has no parameter {name!r}.{nearest(name, self.parameters)} "
                    f"Its parameters are listed by `quadcosim list --parameters {self.name}`."
                )
            checked[name] = self._checked(name, variable, value)
        return checked

    def _checked(self, name: str, variable, value):
        """``value`` as the FMU takes it for ``variable``, or a ValueError naming the problem."""
        label, kind = f"{self.name}.{name}", variable.type
        if variable.shape:
            raise ValueError(f"{label} is an array parameter; the master sets scalar parameters only")
        if kind in ("Real", "Float64", "Float32"):
            value = float(value)
            if not math.isfinite(value):
                raise ValueError(f"{label} = {value} is not a finite number")
        elif kind in INTEGER_TYPES:
            if isinstance(value, bool) or int(value) != value:
                raise ValueError(f"{label} = {value!r} must be an integer")
            value = int(value)
            dtype = np.dtype(types_of(self.fmi3)[kind][1])
            low, high = np.iinfo(dtype).min, np.iinfo(dtype).max
            if not low <= value <= high:  # no silent wrap-around
                raise ValueError(f"{label} = {value} is outside the range of an FMI {kind}, {low} to {high}")
        elif kind == "Boolean":
            if value not in (True, False, 0, 1):
                raise ValueError(f"{label} = {value!r} must be true or false")
            value = bool(value)
        elif kind == "String":
            if not isinstance(value, str):
                raise ValueError(f"{label} = {value!r} must be text (a String parameter)")
        elif kind == "Binary":
            if isinstance(value, str):
                try:
                    value = bytes.fromhex(value)
                except ValueError:
                    raise ValueError(f"{label} = {value!r}: give a Binary parameter as bytes or hexadecimal "
                                     "text (\"0a1b\")") from None
            elif not isinstance(value, bytes | bytearray):
                raise ValueError(f"{label} = {value!r}: give a Binary parameter as bytes or hexadecimal text")
            value = bytes(value)
        else:
            raise ValueError(f"{label} is a {kind}; the master sets no {kind} parameter")
        return value

    def vr(self, names) -> np.ndarray:
        """Value references of scalar Real variables ``names`` (FMI 2.0), as a ctypes-ready uint32 array."""
        refs = []
        for name in names:
            variable = self.variables.get(name)
            if variable is None:
                raise KeyError(f"{self.name} has no variable {name!r}.{nearest(name, self.variables)}")
            if variable.type != "Real":
                raise TypeError(f"{self.name}.{name} is {variable.type}; set and get it with set() and get()")
            refs.append(variable.valueReference)
        return np.array(refs, dtype=np.uint32)

    def _signals(self, names) -> list:
        found = []
        for name in names:
            signal = self.signal.get(name)
            if signal is None:
                variable = self.variables.get(name)
                if variable is None or variable.type not in types_of(self.fmi3):
                    known = list(self.signal) + list(self.variables)
                    what = f"a {variable.type}, not a signal" if variable is not None else "no such variable"
                    raise KeyError(f"{self.name} has no numeric variable {name!r} ({what}).{nearest(name, known)}")
                signal = signals_of(variable)[0] if not variable.shape else None
                if signal is None:
                    raise KeyError(f"{self.name}.{name} is an array; name its elements "
                                   f"({', '.join(s.name for s in signals_of(variable)[:3])}, ...)")
            found.append(signal)
        return found

    def texts(self) -> dict[str, str]:
        """The present values of the FMU's String and Binary variables (Binary as hexadecimal),
        by name: what of them a run records, once, as it records parameters."""
        found = {}
        for variable in self.variables.values():
            if variable.type in TEXT_TYPES and not variable.shape:
                getter = getattr(self._slave, f"get{variable.type}")
                value = self._call(lambda getter=getter, variable=variable: getter([variable.valueReference])[0],
                                   f"fmi{3 if self.fmi3 else 2}Get{variable.type}({variable.name})")
                found[variable.name] = value.hex() if isinstance(value, bytes) and variable.type == "Binary" \
                    else value.decode(errors="replace") if isinstance(value, bytes) else str(value)
        return found

    # ------------------------------------------------------------------ the loop's calls
    def setter(self, names, addresses) -> list[CEntry]:
        """The C calls that set inputs (or parameters, before a step) ``names`` from the float64
        values at ``addresses``, in a loop, with no look-up.

        Parameters
        ----------
        names : sequence of str
            Signal names (an FMI 3.0 array: all its elements).
        addresses : sequence of int
            Address of each one's float64 value (on the bus).

        Returns
        -------
        list of quadcosim.orchestrator.fmi_types.CEntry
            Calls of the signature of ``fmi2SetReal``; an FMI 2.0 FMU's Real variables from
            consecutive addresses take the FMU's own ``fmi2SetReal``, one call per run.
        """
        return self._entries(names, addresses, "Set")

    def getter(self, names, addresses) -> list[CEntry]:
        """The C calls that write outputs ``names`` to the float64 values at ``addresses``
        (as :meth:`setter`)."""
        return self._entries(names, addresses, "Get")

    def stepper(self) -> CEntry:
        """The C call of one communication step, of the signature of ``fmi2DoStep``
        ``(component, t, h, 1)``: time ``t`` (s), step ``h`` (s)."""
        return CEntry(address(self.raw_do_step), self.component, 0, 0, 0, "fmi2DoStep")

    def _entries(self, names, addresses, direction: str) -> list[CEntry]:
        pairs = sorted(zip(self._signals(names), addresses, strict=True), key=lambda pair: pair[1])
        if not pairs:
            return []
        if not (self.all_real or all(s.variable.type == "Real" for s, _ in pairs)):
            return [typed_entry(self._function, self.component, self.fmi3, pairs, direction)]
        entries, i = [], 0
        raw = self.raw_set_real if direction == "Set" else self.raw_get_real
        while i < len(pairs):  # one fmi2SetReal/fmi2GetReal per run of consecutive addresses
            j = i + 1
            while j < len(pairs) and pairs[j][1] == pairs[j - 1][1] + 8:
                j += 1
            refs = np.array([s.variable.valueReference for s, _ in pairs[i:j]], dtype=np.uint32)
            entries.append(CEntry(address(raw), self.component, refs.ctypes.data, len(refs), pairs[i][1],
                                  f"fmi2{direction}Real", refs))
            i = j
        return entries

    # ------------------------------------------------------------------ slow path (by name)
    def set(self, names, values):
        """Set inputs (or parameters, before a step) by signal name, of any numeric type.

        Parameters
        ----------
        names : sequence of str
            Signal names.
        values : array_like
            Their values, in the units of the model description (SI); an integer input takes
            the nearest integer, a Boolean one true for any value but zero.
        """
        buffer = np.ascontiguousarray(values, dtype=np.float64).reshape(-1)
        if self.all_real:  # the FMU's own fmi2SetReal, straight from the values
            refs = self.vr(names)
            status = self.raw_set_real(self.component_arg, ctypes.c_void_p(refs.ctypes.data),
                                       ctypes.c_size_t(len(refs)), ctypes.c_void_p(buffer.ctypes.data))
            if failed(status):
                raise FMUError(self.name, "fmi2SetReal", status, self.time, list(self.log))
            return
        self._run(names, buffer, "Set")

    def get(self, names) -> np.ndarray:
        """Signals by name, of any numeric type, as float64, in the units of the model
        description (SI).

        Parameters
        ----------
        names : sequence of str
            Signal names.

        Returns
        -------
        ndarray
            Their present values.
        """
        buffer = np.empty(len(names))
        if self.all_real:
            refs = self.vr(names)
            status = self.raw_get_real(self.component_arg, ctypes.c_void_p(refs.ctypes.data),
                                       ctypes.c_size_t(len(refs)), ctypes.c_void_p(buffer.ctypes.data))
            if failed(status):
                raise FMUError(self.name, "fmi2GetReal", status, self.time, list(self.log))
            return buffer
        self._run(names, buffer, "Get")
        return buffer

    def _run(self, names, buffer: np.ndarray, direction: str):
        signals_ = self._signals(names)
        if len(buffer) != len(signals_):
            raise ValueError(f"{self.name}: {len(signals_)} signals and {len(buffer)} values")
        wanted = {id(s.variable) for s in signals_ if s.variable.shape}
        whole = [s for s in self.signal.values() if id(s.variable) in wanted and s not in signals_]
        if whole:  # an FMI 3.0 array is set and got whole: the other elements, as they are
            extra = self.get([s.name for s in whole]) if direction == "Set" else np.empty(len(whole))
            signals_, buffer_all = signals_ + whole, np.concatenate([buffer, extra])
        else:
            buffer_all = buffer
        addresses = [buffer_all.ctypes.data + 8 * k for k in range(len(signals_))]
        for entry in self._entries([s.name for s in signals_], addresses, direction):
            status = _SET_OR_GET(entry.function)(entry.component, entry.vr, entry.n, entry.values)
            if failed(status):
                raise FMUError(self.name, entry.label, status, self.time, list(self.log))
        if buffer_all is not buffer:
            buffer[:] = buffer_all[:len(buffer)]

    def step(self, t: float, h: float):
        """Advance one communication step.

        Parameters
        ----------
        t : float
            Present communication time (s).
        h : float
            Step size (s), positive.
        """
        status = self.raw_do_step(self.component_arg, ctypes.c_double(t), ctypes.c_double(h), ctypes.c_int(1))
        if failed(status):
            raise FMUError(self.name, "fmi2DoStep", status, t, list(self.log))
        self.time = t + h

    def terminated(self) -> bool:
        """Whether the FMU asked to end the simulation in its last step (FMI 2.0: a ``fmi2DoStep``
        that returned Discard with ``fmi2Terminated`` true)."""
        from fmpy.fmi2 import fmi2Terminated

        try:
            return self._slave.getBooleanStatus(fmi2Terminated)
        except Exception:  # an FMU without the status functions: not known, not claimed
            return False

    def close(self):
        """Terminate and free the instance (once; an instance in error is freed all the same)."""
        if not getattr(self, "closed", True):
            try:
                self._slave.terminate()
            except Exception:  # an FMU in error state may refuse terminate; free it anyway
                pass
            self._free()
            _logs.pop(self._instance_name.encode(), None)
            self.closed = True

    def _free(self):
        self._slave.fmi2FreeInstance(self.component)

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass


def signals_of(variable) -> list:
    """The signals of one variable (:func:`quadcosim.orchestrator.fmi_types.element_names`)."""
    from quadcosim.orchestrator.fmi_types import Signal, element_names

    return [Signal(n, variable, k) for k, n in enumerate(element_names(variable.name, tuple(variable.shape or ())))]


# ------------------------------------------------------------------ FMI 3.0
_STEP = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int)


def _logger(log: FMULog):
    """An FMI 3.0 log function that keeps the instance's messages in ``log``, as FMI 2.0's does."""
    def on_log(environment, status, category, message):
        log.keep(status, message)
    return on_log


class FMU3Instance(FMUInstance):
    """An instantiated and initialized FMI 3.0 Co-Simulation FMU (made by :class:`FMUInstance`
    for an FMI 3.0 file; the same parameters and methods).

    What the master supports of FMI 3.0 Co-Simulation: variables of types Float32, Float64, Int8
    to UInt64, Boolean and Enumeration as signals (an array as one signal per element), String
    and Binary parameters set at initialization and recorded as text. The FMU is instantiated
    without event mode and without early return, and stepped with ``fmi3DoStep`` at the
    master's communication steps; an FMU that asks to end the simulation (``terminateSimulation``)
    ends the run with what was recorded. Clocks need event mode, which the master does not run:
    an FMU with clocks is refused, by name (:func:`fmu_file`).

    Parameters
    ----------
    model : str
        Path of an FMI 3.0 ``.fmu`` file.
    parameters : dict, optional
        Overrides of parameter start values, by variable name.
    name : str, optional
        Instance (block) name used in messages.
    start_time : float
        Start time (s).
    """

    fmi3 = True

    def _open(self):
        description = self.description
        self._slave = FMU3Slave(
            guid=description.guid,
            unzipDirectory=_unzip(self.path),
            modelIdentifier=description.coSimulation.modelIdentifier,
            instanceName=self._instance_name,
        )
        # fmpy wraps the callback and keeps it with the slave
        self._call(lambda: self._slave.instantiate(logMessage=_logger(self.log)), "fmi3InstantiateCoSimulation")
        self.component = self._slave.component
        self.raw_do_step = self._slave.dll["fmi3DoStep"]
        self.component_arg = ctypes.c_void_p(self.component)
        self._step = self.stepper()
        self._step_call = _STEP(self._step.function)

    def _initialize(self, overrides: dict, start_time: float):
        self._call(lambda: self._slave.enterInitializationMode(startTime=start_time), "fmi3EnterInitializationMode")
        self._set_parameters(overrides)
        self._call(self._slave.exitInitializationMode, "fmi3ExitInitializationMode")

    def stepper(self):
        """The C call of one communication step (``fmi3DoStep``, without event mode or early
        return), of the signature of ``fmi2DoStep``: see :meth:`FMUInstance.stepper`."""
        return step3_entry(self.raw_do_step, self.component)

    def step(self, t: float, h: float):
        """Advance one communication step from ``t`` (s) by ``h`` (s)."""
        status = self._step_call(self._step.component, t, h, 1)
        if failed(status):
            raise FMUError(self.name, "fmi3DoStep", status, t, list(self.log))
        self.time = t + h

    def terminated(self) -> bool:
        """Whether the FMU asked to end the simulation in its last ``fmi3DoStep``."""
        return bool(self._step.keep[0].terminated)

    def _free(self):
        self._slave.fmi3FreeInstance(self.component)
