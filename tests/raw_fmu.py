"""An FMU driven through its bare FMI 2.0 functions: every call returns its status instead of
raising, so that tests can make calls no well-behaved master would make and read what the FMU
logged about them."""

from __future__ import annotations

import ctypes
import itertools
import math
from collections import deque
from pathlib import Path

from fmpy import read_model_description
from fmpy.fmi2 import FMU2Slave, fmi2CoSimulation
from quadcosim.fmus import fmu_path
from quadcosim.orchestrator.fmu import _CALLBACKS, _logs, _unzip

_names = itertools.count(1)
LAST_SUCCESSFUL_TIME = 2  # fmi2StatusKind


class RawFMU:
    """One FMU binary; :meth:`instantiate` makes a fresh component of it.

    Parameters
    ----------
    model : str
        Name of a built FMU (``"Quadrotor"``, ``"MotorMagnetics"``, ``"IMU"``).
    """

    def __init__(self, model: str):
        path = fmu_path(model)
        self.model = model
        self.description = read_model_description(str(path))
        variables = self.description.modelVariables
        self.refs = {v.name: v.valueReference for v in variables}
        self.count = {kind: sum(v.type == kind for v in variables) for kind in ("Real", "Integer", "Boolean")}
        self.names = {kind: {v.valueReference: v.name for v in variables if v.type == kind}
                      for kind in ("Real", "Integer", "Boolean")}
        self.outputs = [v.valueReference for v in variables if v.causality == "output"]
        self._slave = FMU2Slave(guid=self.description.guid, unzipDirectory=_unzip(Path(path)),
                                modelIdentifier=self.description.coSimulation.modelIdentifier)
        self.f = self._slave._functions
        self.component = None
        self.log: deque[str] = deque(maxlen=50)
        self._name = b""

    # ------------------------------------------------------------------ life cycle
    def instantiate(self) -> bool:
        """A fresh component (the previous one, if any, is freed); False if refused."""
        self.free()
        self.log.clear()
        self._name = f"{self.model}~raw{next(_names)}".encode()
        _logs[self._name] = self.log
        uri = (Path(self._slave.unzipDirectory) / "resources").as_uri().encode()
        self.component = self.f["fmi2Instantiate"](self._name, fmi2CoSimulation,
                                                   self.description.guid.encode(), uri,
                                                   ctypes.byref(_CALLBACKS), 0, 0)
        return bool(self.component)

    def free(self):
        if self.component:
            self.f["fmi2FreeInstance"](self.component)
            self.component = None
        _logs.pop(self._name, None)

    def initialize(self, start: float = 0.0, parameters: dict | None = None) -> int:
        """setupExperiment, enter, set ``parameters`` (Real, by name), exit: the worst status."""
        statuses = [self.setup(start), self.call("fmi2EnterInitializationMode")]
        for name, value in (parameters or {}).items():
            statuses.append(self.set_real([self.refs[name]], [value]))
        statuses.append(self.call("fmi2ExitInitializationMode"))
        return max(statuses)

    # ------------------------------------------------------------------ calls
    def call(self, function: str, *args) -> int:
        return self.f[function](self.component, *args)

    def setup(self, start: float, stop: float | None = None) -> int:
        return self.call("fmi2SetupExperiment", 0, 0.0, start, stop is not None,
                         0.0 if stop is None else stop)

    def set_real(self, refs, values) -> int:
        n = len(refs)
        return self.call("fmi2SetReal", (ctypes.c_uint32 * n)(*refs), n, (ctypes.c_double * n)(*values))

    def get_real(self, refs) -> tuple[int, list[float]]:
        n = len(refs)
        values = (ctypes.c_double * n)()
        status = self.call("fmi2GetReal", (ctypes.c_uint32 * n)(*refs), n, values)
        return status, list(values)

    def set_integer(self, refs, values) -> int:
        n = len(refs)
        return self.call("fmi2SetInteger", (ctypes.c_uint32 * n)(*refs), n, (ctypes.c_int32 * n)(*values))

    def get_integer(self, refs) -> tuple[int, list[int]]:
        n = len(refs)
        values = (ctypes.c_int32 * n)()
        return self.call("fmi2GetInteger", (ctypes.c_uint32 * n)(*refs), n, values), list(values)

    def set_boolean(self, refs, values) -> int:
        n = len(refs)
        return self.call("fmi2SetBoolean", (ctypes.c_uint32 * n)(*refs), n, (ctypes.c_int32 * n)(*values))

    def get_boolean(self, refs) -> tuple[int, list[int]]:
        n = len(refs)
        values = (ctypes.c_int32 * n)()
        return self.call("fmi2GetBoolean", (ctypes.c_uint32 * n)(*refs), n, values), list(values)

    def do_step(self, t: float, h: float) -> int:
        return self.call("fmi2DoStep", t, h, 1)

    def time(self) -> float:
        """The FMU's last successful time (NaN if it refuses to say)."""
        value = ctypes.c_double(math.nan)
        self.call("fmi2GetRealStatus", LAST_SUCCESSFUL_TIME, ctypes.byref(value))
        return value.value

    def messages(self) -> str:
        return "\n".join(self.log)
