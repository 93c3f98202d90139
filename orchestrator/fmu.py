"""Loading and stepping one FMI 2.0 Co-Simulation FMU through fmpy.

:class:`FMUInstance` does the set-up once (extraction, instantiation, parameters,
initialization) with clear errors, and then exposes the raw ctypes FMI functions and the
value references, so that a hot loop can call them with preallocated buffers.
"""

from __future__ import annotations

import atexit
import ctypes
import difflib
import itertools
import math
import shutil
from collections import deque
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
from fmpy.logging import addLoggerProxy

from fmus import fmu_path

STATUS = ("OK", "Warning", "Discard", "Error", "Fatal", "Pending")
_extracted: dict[tuple[str, float], str] = {}
_logs: dict[bytes, FMULog] = {}  # instance name -> its log
_instances = itertools.count(1)


class FMULog(deque):
    """The last messages of one FMU instance, with a count of its warnings and the first few
    of them (a warning, such as a saturated command, is kept even when later messages push it
    out of the log).

    Parameters
    ----------
    maxlen : int
        Messages kept.
    """

    FIRST = 5

    def __init__(self, maxlen: int = 200):
        super().__init__(maxlen=maxlen)
        self.warnings = 0
        self.first_warnings: list[str] = []


def _on_log(env, instance, status, category, message):
    log = _logs.get(instance)
    if log is not None:
        label = STATUS[status] if 0 <= status < 6 else status
        text = f"[{label}] {message.decode(errors='replace')}"
        log.append(text)
        if status == 1:
            log.warnings += 1
            if len(log.first_warnings) < FMULog.FIRST:
                log.first_warnings.append(text)


# fmpy's native proxy formats the FMU's variadic messages; it keeps one Python logger for the
# whole process, so there is one callback structure and messages are routed by instance name.
_CALLBACKS = fmi2CallbackFunctions()
_LOGGER = fmi2CallbackLoggerTYPE(_on_log)
_CALLBACKS.logger = _LOGGER
_CALLBACKS.allocateMemory = fmi2CallbackAllocateMemoryTYPE(ctypes.CDLL(None).calloc)
_CALLBACKS.freeMemory = fmi2CallbackFreeMemoryTYPE(ctypes.CDLL(None).free)
addLoggerProxy(ctypes.byref(_CALLBACKS))


def status_name(status: int) -> str:
    """The name of an FMI status, or the number an FMU returned that is no status at all."""
    return STATUS[status] if 0 <= status < 6 else f"{status} (no FMI status: taken as a failure)"


def failed(status: int) -> bool:
    """Whether an FMI call failed: any status but OK and Warning (-1 is no success)."""
    return not 0 <= status <= 1


class FMUError(RuntimeError):
    """An FMU refused a call: the block, the time, the status and what the FMU logged.

    Parameters
    ----------
    block : str
        Block (instance) name.
    function : str
        FMI function that failed, e.g. ``"fmi2DoStep"``.
    status : int
        FMI status returned (3 Error, 4 Fatal).
    time : float or None
        Communication time of the call (s).
    log : list of str
        The FMU's last messages.
    """

    def __init__(self, block: str, function: str, status: int, time: float | None, log: list[str]):
        self.block, self.function, self.status, self.time, self.log = block, function, status, time, log
        when = "" if time is None else f" at t = {time:.6g} s"
        logged = "\n  ".join(log[-10:]) if log else "(the FMU logged nothing)"
        super().__init__(
            f"{block}: {function} returned {status_name(status)}{when}.\n"
            f"  FMU log:\n  {logged}"
        )


class ParameterRefused(FMUError, ValueError):
    """An FMU refused the parameter values it was given, at instantiation or initialisation.

    A ``ValueError`` too: it is refused input, which the command line answers with exit 2.
    The message names the block, the call, the values set and what the FMU logged.

    Parameters
    ----------
    error : FMUError
        The refused call.
    overrides : dict
        The parameter values that were set, by variable name.
    model : str
        The FMU's model name, for the command that lists its parameters.
    """

    def __init__(self, error: FMUError, overrides: dict, model: str):
        self.block, self.function, self.status, self.time, self.log = (
            error.block, error.function, error.status, error.time, error.log)
        given = ", ".join(f"{name}={value!r}" for name, value in overrides.items()) or "none (the defaults)"
        logged = "\n  ".join(error.log[-10:]) if error.log else "(the FMU logged nothing)"
        ValueError.__init__(
            self, f"{model} refused its parameters at initialisation ({error.function} returned "
                  f"{status_name(error.status)}). Values set: {given}.\n"
                  f"  FMU log:\n  {logged}\n"
                  f"Give a value in the range the log names (`quadcosim list --parameters {model}` lists each "
                  f"parameter's default and unit).")


_descriptions: dict[tuple, object] = {}


def is_fmu_file(model) -> bool:
    """Whether ``model`` names an FMU file (``"my_motor.fmu"``, a path) rather than a built model."""
    return str(model).lower().endswith(".fmu")


def fmu_file(model) -> Path:
    """The FMU file of ``model``: a built model by name (:func:`fmus.fmu_path`), or a path to any
    FMI 2.0 Co-Simulation FMU, made absolute.

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
        The file is not an FMI 2.0 FMU for Co-Simulation (the message says what it is).
    """
    if not is_fmu_file(model):
        return fmu_path(model)
    path = Path(model).expanduser().absolute()
    if not path.is_file():
        raise FileNotFoundError(f"FMU file {model} not found (looked at {path}); give the path of an .fmu file, or "
                                "a built model's name (IMU, Quadrotor, MotorMagnetics)")
    from orchestrator.fmu_checks import FMURefused, check_archive, check_file

    try:
        check_archive(path)  # before the description is read: no entry of a zip bomb is expanded
        description = model_description(path)
    except FMURefused:
        raise
    except Exception as error:  # fmpy raises several kinds on a file that is not an FMU
        raise ValueError(f"{model} is not a readable FMU: {error}") from None
    if not str(description.fmiVersion).startswith("2."):
        raise ValueError(f"{model} is an FMI {description.fmiVersion} FMU; the master runs FMI 2.0 FMUs (export "
                         "for FMI 2.0 Co-Simulation)")
    if description.coSimulation is None:
        raise ValueError(f"{model} is an FMI 2.0 Model Exchange FMU only; the master runs Co-Simulation FMUs "
                         "(export for FMI 2.0 Co-Simulation, with its own solver)")
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
    """``"did you mean a, b?"`` for the candidates closest to ``name``."""
    close = difflib.get_close_matches(name, list(candidates), n=n, cutoff=0.5)
    return f" Did you mean {', '.join(close)}?" if close else ""


class FMUInstance:
    """One instantiated and initialized FMU.

    Parameters
    ----------
    model : str
        Name of a built FMU (``"Quadrotor"``, ``"MotorMagnetics"``, ``"IMU"``), found by
        :func:`fmus.fmu_path`, or a path to an ``.fmu`` file.
    parameters : dict, optional
        Overrides of parameter start values, by variable name.
    name : str, optional
        Instance (block) name used in messages; defaults to the model name.
    start_time : float
        Start time (s).
    """

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
        self.parameters = [v.name for v in description.modelVariables if v.causality == "parameter"]
        self.inputs = [v.name for v in description.modelVariables if v.causality == "input"]
        self.outputs = [v.name for v in description.modelVariables if v.causality == "output"]
        overrides = self._check_parameters(parameters or {})
        self._instance_name = f"{self.name}#{next(_instances)}"
        _logs[self._instance_name.encode()] = self.log

        self._slave = FMU2Slave(
            guid=description.guid,
            unzipDirectory=_unzip(path),
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
        self.closed = False
        try:
            self._initialize(overrides, start_time)
        except FMUError as error:  # a value the model refuses: refused input, the instance freed
            self.close()
            raise ParameterRefused(error, overrides, path.stem) from None
        except Exception:
            self.close()
            raise

    def _initialize(self, overrides: dict, start_time: float):
        self._call(lambda: self._slave.setupExperiment(startTime=start_time), "fmi2SetupExperiment")
        self._call(self._slave.enterInitializationMode, "fmi2EnterInitializationMode")
        for kind in ("Real", "Integer", "Boolean"):  # one call per type, in the order given
            names = [name for name in overrides if self.variables[name].type == kind]
            if names:
                self._set_many(kind, names, [overrides[name] for name in names])
        self._call(self._slave.exitInitializationMode, "fmi2ExitInitializationMode")

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
            self._call(self._slave.reset, "fmi2Reset")
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
            function()
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
            if variable is None or variable.causality != "parameter":
                raise ValueError(
                    f"{self.name} has no parameter {name!r}.{nearest(name, self.parameters)} "
                    f"Its parameters are listed by `quadcosim list --parameters {self.name}`."
                )
            if variable.type == "Real":
                value = float(value)
                if not math.isfinite(value):
                    raise ValueError(f"{self.name}.{name} = {value} is not a finite number")
            elif variable.type == "Integer":
                if int(value) != value:
                    raise ValueError(f"{self.name}.{name} = {value!r} must be an integer")
                value = int(value)
                if not -2**31 <= value < 2**31:  # an FMI Integer is 32 bits: no silent wrap-around
                    raise ValueError(f"{self.name}.{name} = {value} is outside the range of an FMI Integer, "
                                     f"{-2**31} to {2**31 - 1}")
            elif variable.type == "Boolean":
                if value not in (True, False, 0, 1):
                    raise ValueError(f"{self.name}.{name} = {value!r} must be true or false")
                value = bool(value)
            checked[name] = value
        return checked

    def _set_many(self, kind: str, names: list[str], values: list):
        setter = {"Real": self._slave.setReal, "Integer": self._slave.setInteger,
                  "Boolean": self._slave.setBoolean}[kind]
        refs = [self.variables[name].valueReference for name in names]
        label = f"fmi2Set{kind}({', '.join(names)})"
        self._call(lambda: setter(refs, values), label)

    def vr(self, names) -> np.ndarray:
        """Value references of Real variables ``names``, as a ctypes-ready uint32 array."""
        refs = []
        for name in names:
            variable = self.variables.get(name)
            if variable is None:
                raise KeyError(f"{self.name} has no variable {name!r}.{nearest(name, self.variables)}")
            if variable.type != "Real":
                raise TypeError(f"{self.name}.{name} is {variable.type}; only Real signals are wired")
            refs.append(variable.valueReference)
        return np.array(refs, dtype=np.uint32)

    # ------------------------------------------------------------------ slow path (by name)
    def set(self, names, values):
        """Set Real inputs (or parameters, before a step) by name.

        Parameters
        ----------
        names : sequence of str
            Variable names.
        values : array_like
            Their values, in the units of the model description (SI).
        """
        refs = self.vr(names)
        buffer = np.ascontiguousarray(values, dtype=np.float64)
        status = self.raw_set_real(self.component_arg, ctypes.c_void_p(refs.ctypes.data), ctypes.c_size_t(len(refs)),
                                   ctypes.c_void_p(buffer.ctypes.data))
        if failed(status):
            raise FMUError(self.name, "fmi2SetReal", status, self.time, list(self.log))

    def get(self, names) -> np.ndarray:
        """Real variables by name, in the units of the model description (SI).

        Parameters
        ----------
        names : sequence of str
            Variable names.

        Returns
        -------
        ndarray
            Their present values.
        """
        refs = self.vr(names)
        buffer = np.empty(len(refs))
        status = self.raw_get_real(self.component_arg, ctypes.c_void_p(refs.ctypes.data), ctypes.c_size_t(len(refs)),
                                   ctypes.c_void_p(buffer.ctypes.data))
        if failed(status):
            raise FMUError(self.name, "fmi2GetReal", status, self.time, list(self.log))
        return buffer

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

    def close(self):
        """Terminate and free the instance (once; an instance in error is freed all the same)."""
        if not getattr(self, "closed", True):
            try:
                self._slave.terminate()
            except Exception:  # an FMU in error state may refuse terminate; free it anyway
                pass
            self._slave.fmi2FreeInstance(self.component)
            _logs.pop(self._instance_name.encode(), None)
            self.closed = True

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass
