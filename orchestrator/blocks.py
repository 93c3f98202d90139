"""Block contracts: Python blocks and FMU blocks.

A block has named scalar inputs and outputs. At each of its steps (every ``period`` macro
steps) the master gives a Python block its inputs ``u`` and a view ``y`` of its outputs, both
float64 arrays in declaration order; the block writes ``y`` in place. An FMU block sets its
inputs, reads its outputs, and advances its state by one communication step.

Blocks are stepped in dependency order (Gauss-Seidel): a block whose outputs depend on its
present inputs (direct feedthrough) runs after the blocks that feed it. A Python block that
declares no feedthrough sees, from blocks ordered after it, the values of the previous macro
step: a unit delay.

A Python block's parameters, the values a setting may change before a run (``--set
Controller.kp_yaw=50``, :meth:`quadcosim.orchestrator.System.set_parameter`), reach it through
:meth:`Block.parameter_values` and :meth:`Block.set_parameter`. A class that declares them
(:attr:`Block.parameter_units`) has its settings checked before any block is built; one that
does not offers its public numeric attributes, checked once it is built.

A block may also expose its step as compiled code (:meth:`Block.compiled`): a C-callable
function that the chunk runner calls for whole chunks of steps without returning to Python.
Such a block keeps its Python ``step`` too, and both must compute the same numbers from the
same memory (the per-step master and the chunk runner give bit-identical results).
"""

from __future__ import annotations

import numbers
from typing import ClassVar, NamedTuple

import numpy as np

#: C signature of a compiled block step: ``int step(double t, const double *u, double *y, double *data)``,
#: time ``t`` (s), inputs ``u`` and outputs ``y`` in declaration order, ``data`` the block's own
#: state and parameters; it returns 0, or a non-zero code that stops the run.
COMPILED_SIGNATURE = "int32(float64, CPointer(float64), CPointer(float64), CPointer(float64))"


def source_fingerprint(*modules) -> int:
    """A 60-bit fingerprint of the source files of ``modules`` (module objects).

    A compiled step cached by numba (``cfunc(..., cache=True)``) is reused while its own file
    is unchanged, even when a function it calls from another file has changed; a closure
    variable holding this fingerprint enters numba's cache key, so that the cache follows
    those files too.

    Returns
    -------
    int
        From the SHA-256 of the files' bytes, in the order given.
    """
    import hashlib
    from pathlib import Path

    digest = hashlib.sha256()
    for module in modules:
        digest.update(Path(module.__file__).read_bytes())
    return int.from_bytes(digest.digest()[:8], "little") >> 4


class CompiledStep(NamedTuple):
    """A block's step as a C function, for the chunk runner.

    Parameters
    ----------
    address : int
        Address of a function of signature :data:`COMPILED_SIGNATURE` (e.g. a numba ``cfunc``'s
        ``address``).
    inputs : ndarray
        float64 buffer, at least as long as the block's inputs: the runner gathers the inputs
        into its first elements before each call.
    data : ndarray
        float64 state, parameters and scratch the function reads and writes; the same memory
        the Python ``step`` uses, so both forms continue one another.
    keep : object
        Whatever must stay alive while the address is called (the compiled function object).
    """

    address: int
    inputs: np.ndarray
    data: np.ndarray
    keep: object = None


#: Attributes of every block that are not parameters, though some are numbers.
NOT_PARAMETERS = ("name", "period", "feedthrough", "inputs", "outputs")


class Block:
    """Base class of Python blocks.

    Subclasses set ``inputs`` and ``outputs`` (tuples of names), may set ``feedthrough``
    (``True``: every output depends on the present inputs; ``False``: none does) and
    implement :meth:`step`. Its parameters are declared by :attr:`parameter_units`, read by
    :meth:`parameter_values` and set by :meth:`set_parameter`.

    Parameters
    ----------
    name : str
        Block name, without a dot (signals are written ``"Block.signal"``).
    period : int
        The block runs every ``period`` macro steps; its own step is ``period * dt`` (s).
    """

    inputs: tuple[str, ...] = ()
    outputs: tuple[str, ...] = ()
    feedthrough: bool = True
    #: The parameters the class declares, name to unit (``"1/s^2"``; ``"1"`` for a pure number):
    #: a setting of one is checked before any block is built. Empty (the default): the block's
    #: parameters are its public numeric attributes, known once it is built.
    parameter_units: ClassVar[dict[str, str]] = {}

    def __init__(self, name: str, period: int = 1):
        if int(period) != period or period < 1:
            raise ValueError(f"{name}: period must be a positive integer number of macro steps, not {period}")
        self.name = name
        self.period = int(period)

    @property
    def feedthrough_inputs(self) -> set[str]:
        """Inputs whose present value the outputs depend on (orders the blocks)."""
        return set(self.inputs) if self.feedthrough else set()

    def start(self, t0: float, dt: float) -> None:
        """Reset the state before a run.

        Parameters
        ----------
        t0 : float
            Start time (s).
        dt : float
            This block's own step, ``period`` macro steps (s).
        """

    def step(self, t: float, u: np.ndarray, y: np.ndarray) -> None:
        """Compute the outputs at time ``t`` (s) from the inputs ``u``, writing ``y`` in place."""
        raise NotImplementedError(f"{type(self).__name__} must implement step(t, u, y)")

    def parameter_values(self) -> dict:
        """The parameters a setting may change, by name, and their present values.

        Returns
        -------
        dict
            Name to value (a number, or a bool), sorted by name: the declared parameters
            (:attr:`parameter_units`, read as attributes), else the public numeric attributes.
        """
        if self.parameter_units:
            return {name: getattr(self, name) for name in sorted(self.parameter_units)}
        return dict(sorted((k, v) for k, v in vars(self).items()
                           if not k.startswith("_") and k not in NOT_PARAMETERS and isinstance(v, numbers.Real)))

    @classmethod
    def check_parameter(cls, name: str, value):
        """A value of declared parameter ``name`` checked before any block is built: returned as
        it will be set, or refused (ValueError, saying what is expected). The default takes any
        finite number in the declared unit (the caller checks that much)."""
        return value

    def set_parameter(self, name: str, value) -> None:
        """Set parameter ``name`` (one of :meth:`parameter_values`) to ``value`` before the run.

        Parameters
        ----------
        name : str
            The parameter's name.
        value : float, int or bool
            Its value, in its unit, of the type of its present value (checked by the caller,
            :func:`quadcosim.orchestrator.parameters.resolve`); a block that keeps the value
            elsewhere, or checks more, overrides this method and raises ValueError on a bad one.
        """
        setattr(self, name, value)

    def compiled(self) -> CompiledStep | None:
        """The step as compiled code, after :meth:`start`; ``None`` (the default): Python only.

        Returns
        -------
        CompiledStep or None
            The C-callable step and its memory; the chunk runner calls it instead of
            :meth:`step`. A Python-only block costs one return to Python per step.
        """
        return None

    def close(self) -> None:
        """Release resources after a run."""


class Table(Block):
    """Outputs read from a table sampled at the block's own rate (for scripted signals).

    Parameters
    ----------
    name : str
        Block name.
    outputs : sequence of str
        Output names.
    values : (n, len(outputs)) array, or callable
        Row ``k`` is output at the block's ``k``-th step; the last row is held after the end.
        A callable ``values(t)`` maps an array of times ``t`` (s) to the rows at those times;
        it is evaluated a chunk of rows at a time as the run goes, so that a long run never
        holds its whole table in memory.
    period : int
        Runs every ``period`` macro steps.
    chunk : int
        Rows evaluated at once from a callable.
    units : dict, optional
        Unit of each output by name, as the variable tables write them (``"rad"``, ``"1"``);
        they label the results and plots.
    """

    feedthrough = False

    def __init__(self, name: str, outputs, values, period: int = 1, chunk: int = 4096, units: dict | None = None):
        super().__init__(name, period)
        self.outputs = tuple(outputs)
        self.units = dict(units or {})
        self.function = values if callable(values) else None
        self.chunk = int(chunk)
        if self.function is None:
            self.values = self._checked(np.ascontiguousarray(values, dtype=float))
        else:  # evaluated once here so that a bad function fails before the run
            self.values = None
            self._checked(np.ascontiguousarray(self.function(np.zeros(1)), dtype=float))

    def _checked(self, values: np.ndarray) -> np.ndarray:
        if values.ndim != 2 or values.shape[1] != len(self.outputs):
            raise ValueError(f"{self.name}: values must have shape (n, {len(self.outputs)}), not {values.shape}")
        if not np.isfinite(values).all():
            raise ValueError(f"{self.name}: the table holds NaN or Inf")
        return values

    def start(self, t0, dt):
        """Rewind the table to its first row; ``t0`` (s) is the start time, ``dt`` (s) the block's step."""
        if self.function is None:
            self._rows = iter(self.values)
            self._last = self.values[-1]
            return
        self._t0, self._dt, self._next = t0, dt, 0
        self._rows = iter(())

    def step(self, t, u, y):
        if self.function is None:
            y[:] = next(self._rows, self._last)
            return
        row = next(self._rows, None)
        if row is None:
            _, rows = self.segment(self._next)
            self._next += self.chunk
            self._rows = iter(rows)
            row = next(self._rows)
        y[:] = row

    def segment(self, row: int) -> tuple[int, np.ndarray]:
        """The rows of the table around row ``row`` (the block's ``row``-th step).

        Parameters
        ----------
        row : int
            Index of a step of the block (0 at the start time).

        Returns
        -------
        first : int
            Index of the first row returned.
        rows : ndarray
            ``(n, len(outputs))``: the whole table (``first`` = 0, the last row held after
            it), or, for a callable, its chunk of ``chunk`` rows at times ``t0 + k dt`` (s),
            ``k = first, first + 1, ...``, with ``first`` a multiple of ``chunk``.
        """
        if self.function is None:
            return 0, self.values
        first = row // self.chunk * self.chunk
        k = first + np.arange(self.chunk)
        return first, self._checked(np.ascontiguousarray(self.function(self._t0 + k * self._dt), dtype=float))


class Constant(Block):
    """Constant outputs.

    Parameters
    ----------
    name : str
        Block name.
    values : dict of str to float
        Output name to its value (in the unit of whatever it feeds).
    ties : str, optional
        The input this block ties off, when :meth:`System.set_input` made it; the diagram
        draws such a block as a note on that input rather than as a block.
    """

    feedthrough = False

    def __init__(self, name: str, values: dict[str, float], ties: str | None = None):
        super().__init__(name)
        self.outputs = tuple(values)
        self.values = np.array([float(v) for v in values.values()])
        self.ties = ties

    def step(self, t, u, y):
        y[:] = self.values


def is_path(model) -> bool:
    """Whether ``model`` is an FMU file's path rather than a built model's name."""
    from quadcosim.orchestrator.fmu import is_fmu_file

    return model is not None and is_fmu_file(model)


class FMUBlock:
    """A block backed by an FMU: a built plant model, or any FMI 2.0 or 3.0 Co-Simulation FMU by path.

    Parameters
    ----------
    name : str
        Block name (the lab's diagram names: ``Quadrotor``, ``MotorMagnetics``, ``IMU``).
    model : str or pathlib.Path, optional
        A built model's name (``"IMU"``), or the path of an FMU file of any exporter
        (``"my_motor.fmu"``: OpenModelica, Dymola, Simulink, pythonfmu, ...); defaults to ``name``.
        Its numeric inputs and outputs become the block's, by their variable names: every FMI
        type, an FMI 3.0 array as one signal per element (:mod:`quadcosim.orchestrator.fmi_types`).
    parameters : dict, optional
        Parameter overrides, by FMU variable name.
    period : int
        Runs every ``period`` macro steps, with a communication step of ``period * dt``.
    isolated : bool, optional
        Run the FMU in a worker process of its own (True) or in this one (False); by default an
        FMU this project did not build runs isolated (:mod:`quadcosim.orchestrator.isolated`).

    Attributes
    ----------
    dtypes : dict
        The NumPy type of each signal that is not float64 (``{"counter": "int32"}``): the
        record keeps it, and its files store the signal with it.
    """

    def __init__(self, name: str, model: str | None = None, parameters: dict | None = None, period: int = 1,
                 isolated: bool | None = None):
        from quadcosim.orchestrator.fmi_types import dtypes, is_parameter, signals, unit
        from quadcosim.orchestrator.fmu import fmu_file, model_description

        if int(period) != period or period < 1:
            raise ValueError(f"{name}: period must be a positive integer number of macro steps, not {period}")
        self.name = name
        self.path = fmu_file(model or name)
        self.model = str(self.path) if is_path(model) else (model or name)  # a file: its absolute path
        self.parameters = dict(parameters or {})
        self.period = int(period)
        self.isolated = isolated
        description = model_description(self.path)
        variables = description.modelVariables
        inputs, outputs = signals(description, "input"), signals(description, "output")
        self.inputs = tuple(s.name for s in inputs)
        self.outputs = tuple(s.name for s in outputs)
        self.dtypes = dtypes(description, self.inputs + self.outputs)
        self.parameter_names = tuple(v.name for v in variables if is_parameter(v))
        self.units = {s.name: unit(s.variable) for s in outputs}  # labels the results
        self.input_units = {s.name: unit(s.variable) for s in inputs}
        unknown = set(self.parameters) - set(self.parameter_names)
        if unknown:
            from quadcosim.orchestrator.fmu import nearest

            name0 = sorted(unknown)[0]
            raise ValueError(f"{name} ({self.model}) has no parameter {name0!r}.{nearest(name0, self.parameter_names)}")
        fed = set()
        for output in description.outputs:
            fed |= {d.name for d in (output.dependencies or [])}
        self.feedthrough_inputs = {s.name for s in inputs if s.variable.name in fed}
        self.instance = None
        texts = [v.name for v in variables if v.causality in ("input", "output") and v.type in ("String", "Binary")]
        if texts:  # said once, rather than lost silently
            import warnings

            warnings.warn(f"{name}: {', '.join(texts)} {'is' if len(texts) == 1 else 'are'} String or Binary, not "
                          "signals: an input keeps its start value unless set as a parameter, and each one's value "
                          "after initialization is recorded in the result's meta['texts']", RuntimeWarning,
                          stacklevel=2)

    def instantiate(self, t0: float):
        """Instantiate and initialize the FMU, parameters set.

        Parameters
        ----------
        t0 : float
            Start time (s).

        Returns
        -------
        quadcosim.orchestrator.fmu.FMUInstance
            The live instance, also kept as ``self.instance``.
        """
        from quadcosim.orchestrator import pool

        self.instance = pool.acquire(self.model, self.parameters, name=self.name, start_time=t0,
                                     isolated=self.isolated)
        return self.instance

    def close(self):
        """Free the FMU instance after a run (or keep it for the next run, when this process
        reuses instances: :mod:`quadcosim.orchestrator.pool`)."""
        if self.instance is not None:
            from quadcosim.orchestrator import pool

            pool.release(self.instance)
            self.instance = None
