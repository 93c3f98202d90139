"""The estimator contract: what a block must provide to fly in the place of ``Quaternion_estim``.

A closed-loop scenario (``tp``) takes an attitude estimator of the user's in the place of its
``Quaternion_estim`` block, from Python (``tp.build(options, estimator=MyBlock())``,
``quadcosim.scenarios.run("tp", ..., estimator=MyBlock)`` or ``system.replace("Quaternion_estim", block)``)
or from the command line (``quadcosim run tp --estimator my_filter.py:MyBlock``). The block is
an :class:`quadcosim.orchestrator.Block`; its Python ``step(t, u, y)`` is the whole contract, and a
compiled form, where the master offers one, is an optional speed-up that must compute the same
outputs.

Inputs (any subset of :data:`INPUTS`, by name; each is wired from the IMU block)
    ``acc_x, acc_y, acc_z``  specific force (m/s^2, body frame FRD; about ``(0, 0, -9.81)`` at rest),
    ``gyro_x, gyro_y, gyro_z``  angular rate (rad/s, body frame),
    ``magneto_x, magneto_y, magneto_z``  magnetic field (T, body frame),
    ``R_reel_11 .. R_reel_33``  the true rotation body to NED, row-major (for filters fed the
    true attitude, as the lab's passive filter was; an estimator proper does not read it).

Outputs (:data:`REQUIRED`, in any order, each written at every step)
    ``q_est0..3``  attitude quaternion, body to NED, scalar first, unit norm (1),
    ``theta_est1..3``  Z-Y-X Euler angles: roll, pitch, yaw (rad),
    ``b_est_x, b_est_y, b_est_z``  gyro-bias estimate (rad/s, body; zeros for a filter
    without one),
    ``omega_est_x..z``  angular rate for the controller, ``gyro - b_est`` (rad/s, body).
    With ``feedback=estimate`` the controller flies on ``q_est`` and ``omega_est``; the report
    scores ``theta_est`` against the truth and ``b_est`` against the IMU's true bias. Other
    outputs (``acc_weight, mag_weight, at_rest``, anything else) are recorded as well. A
    ``units`` attribute, ``{output: unit}`` (:data:`UNITS` for these), labels the outputs in
    plots and result files.

Rate and timing
    The scenario runs the block at the IMU's rate: its ``period`` is the IMU's, in macro steps,
    and ``start(t0, dt)`` receives its own step ``dt`` (s) before the run. The block has direct
    feedthrough (the default of :class:`quadcosim.orchestrator.Block`): it reads the present IMU sample.

Construction and parameters
    Given as a class (``--estimator module:Class``), the block is built as
    ``Class(period=..., q0=...)``: the IMU's period and the vehicle's initial attitude (body to
    NED, scalar first), each if the constructor takes it (a plain :class:`quadcosim.orchestrator.Block`
    subclass is built as ``Class(name, period=...)``). Given as an instance, the scenario sets
    its ``period`` to the IMU's. A Python block's parameters are its public numeric attributes:
    ``--set Quaternion_estim.beta=0.1`` sets ``beta`` before the run.

:class:`AttitudeEstimator` fills in everything but the filter: a subclass implements
:meth:`AttitudeEstimator.update` on ``self.q`` (and ``self.bias``); the README's Madgwick
filter is one.
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import sys
from pathlib import Path

import numpy as np
from quadcosim.estimators.quaternions import euler_from_quaternion
from quadcosim.orchestrator.blocks import Block

from quadcosim.infra.errors import UsageError

MEASUREMENTS = ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z", "magneto_x", "magneto_y", "magneto_z")
R_REEL = tuple(f"R_reel_{i}{j}" for i in range(1, 4) for j in range(1, 4))
INPUTS = MEASUREMENTS + R_REEL
REQUIRED = ("q_est0", "q_est1", "q_est2", "q_est3", "theta_est1", "theta_est2", "theta_est3",
            "b_est_x", "b_est_y", "b_est_z", "omega_est_x", "omega_est_y", "omega_est_z")
# where AttitudeEstimator reads its inputs and writes its outputs (the order of the names above)
ACC, GYRO, MAG, REEL = slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 18)
Q, THETA, BIAS, OMEGA = slice(0, 4), slice(4, 7), slice(7, 10), slice(10, 13)
UNITS = {**dict.fromkeys(REQUIRED[Q], "1"), **dict.fromkeys(REQUIRED[THETA], "rad"),
         **dict.fromkeys(REQUIRED[BIAS] + REQUIRED[OMEGA], "rad/s")}
assert MEASUREMENTS[GYRO] == ("gyro_x", "gyro_y", "gyro_z") and REQUIRED[OMEGA][0] == "omega_est_x"


class AttitudeEstimator(Block):
    """An estimator block of the contract, with only the filter left to write.

    A subclass implements :meth:`update`, which advances ``self.q`` (body to NED, scalar
    first) and, for a filter that estimates it, ``self.bias`` (rad/s) by one sample of
    ``self.dt`` seconds. The block writes every output of :data:`REQUIRED` from them.

    Parameters
    ----------
    name : str
        Block name; the scenario places it as ``Quaternion_estim``.
    period : int
        Runs every ``period`` macro steps (the scenario sets the IMU's).
    q0 : (4,) array, optional
        Initial attitude, body to NED, scalar first; the scenario gives the vehicle's initial
        attitude when built from a class, identity otherwise.
    """

    inputs = MEASUREMENTS
    outputs = REQUIRED
    units = UNITS  # of the outputs, for plots and result files

    def __init__(self, name: str = "Quaternion_estim", period: int = 1, q0=None):
        super().__init__(name, period)
        self.q0 = None if q0 is None else _unit_quaternion(q0)
        # a filter fed the true rotation (the lab's passive filter) declares it: update(acc, gyro, mag, R_reel)
        self.reads_reel = "R_reel" in inspect.signature(self.update).parameters
        if self.reads_reel:
            self.inputs = MEASUREMENTS + R_REEL

    def start(self, t0, dt):
        """Reset: ``self.q`` to ``q0``, ``self.bias`` to zero.

        Parameters
        ----------
        t0 : float
            Start time (s).
        dt : float
            The block's step (s), kept as ``self.dt``.
        """
        self.dt = dt
        self.q = np.array((1.0, 0.0, 0.0, 0.0)) if self.q0 is None else self.q0.copy()
        self.bias = np.zeros(3)

    def update(self, acc: np.ndarray, gyro: np.ndarray, mag: np.ndarray) -> None:
        """Advance ``self.q`` (and ``self.bias``) by one sample.

        A filter fed the true attitude (as the lab's passive filter was) declares a fourth
        parameter, ``update(self, acc, gyro, mag, R_reel)``: the block then reads the IMU's
        ``R_reel_11 .. R_reel_33`` and passes them as a (3, 3) array, the true rotation body to
        NED.

        Parameters
        ----------
        acc : (3,) array
            Specific force (m/s^2, body).
        gyro : (3,) array
            Angular rate (rad/s, body).
        mag : (3,) array
            Magnetic field (T, body).
        """
        raise NotImplementedError(f"{type(self).__name__} must implement update(acc, gyro, mag)")

    def step(self, t, u, y):
        if self.reads_reel:
            self.update(u[ACC], u[GYRO], u[MAG], u[REEL].reshape(3, 3))
        else:
            self.update(u[ACC], u[GYRO], u[MAG])
        y[Q] = self.q
        euler_from_quaternion(self.q, y[THETA])
        y[BIAS] = self.bias
        y[OMEGA] = u[GYRO] - self.bias


def _unit_quaternion(q) -> np.ndarray:
    q = np.asarray(q, dtype=float)
    if q.shape != (4,) or not np.isfinite(q).all() or not np.linalg.norm(q) > 0:
        raise ValueError(f"q0 {q!r} must be a non-zero quaternion (q0, q1, q2, q3)")
    return q / np.linalg.norm(q)


def load(spec: str) -> type:
    """The class named by ``spec``: ``"package.module:Class"``, or ``"path/to/file.py:Class"``.

    A module is looked for in the working directory first, then on the Python path. Loading
    it executes its top-level code, as ``import`` does. The working directory is on the path only
    while the module is imported (for its own imports of its neighbours): a file there named as a
    standard module (``fractions.py``) does not replace that module for the rest of the run.

    Raises
    ------
    ValueError
        Malformed ``spec``, a module or file that cannot be imported, or no such class.
    """
    where, colon, name = str(spec).rpartition(":")
    if not colon or not where or not name:
        raise ValueError(f"estimator {spec!r}: write module:Class or file.py:Class")
    try:
        if where.endswith(".py") or "/" in where:
            from quadcosim.infra.inputs import regular_file

            path = Path(where).resolve()
            if not path.exists():
                raise ValueError(f"estimator {spec!r}: no file {path}")
            regular_file(path, "the estimator's module", "give a Python file (file.py:Class)",
                         label=f"estimator {spec!r}: {path}")
            module_name = f"quadcosim_user_{path.stem}"
            module = sys.modules.get(module_name)
            if module is None or getattr(module, "__file__", None) != str(path):
                loader = importlib.util.spec_from_file_location(module_name, path)
                module = importlib.util.module_from_spec(loader)
                sys.modules[module_name] = module
                loader.loader.exec_module(module)
        else:
            module = _import_from(where, Path.cwd())
    except ValueError:
        raise
    except Exception as error:  # the user's module failed to import: say so, with its own error
        raise ValueError(f"estimator {spec!r}: importing {where} failed: {type(error).__name__}: {error}") from error
    cls = getattr(module, name, None)
    if cls is None:
        classes = [k for k, v in vars(module).items() if isinstance(v, type) and issubclass(v, Block)
                   and v.__module__ == module.__name__]
        raise ValueError(f"estimator {spec!r}: {where} has no {name!r}"
                         + (f"; its blocks: {', '.join(classes)}" if classes else ""))
    return cls


def _import_from(where: str, folder: Path):
    """Module ``where`` (dotted), from ``folder`` if it holds it, else from the Python path; ``folder``
    is first on ``sys.path`` while the import runs and taken off after it, whatever happens."""
    top = where.partition(".")[0]
    if not ((folder / f"{top}.py").is_file() or (folder / top / "__init__.py").is_file()):
        return importlib.import_module(where)
    stale = sys.modules.get(top)
    if stale is not None and not str(getattr(stale, "__file__", "") or "").startswith(str(folder)):
        raise ValueError(f"estimator module {where!r}: the name {top!r} is already taken by {stale.__name__} "
                         f"({getattr(stale, '__file__', None) or 'built in'}); rename your file, or give it as "
                         f"{top}.py:Class")
    entry = str(folder)
    sys.path.insert(0, entry)
    try:
        importlib.invalidate_caches()
        return importlib.import_module(where)
    finally:
        sys.path.remove(entry)


def label(estimator) -> str:
    """The ``module:Class`` name of an estimator block or class, for titles and metrics."""
    cls = estimator if isinstance(estimator, type) else type(estimator)
    module = cls.__module__.removeprefix("quadcosim_user_")
    return f"{module}:{cls.__qualname__}"


def adopt(estimator, period: int, q0=None, available=INPUTS) -> Block:
    """The block a scenario places as ``Quaternion_estim``, checked against the contract.

    Parameters
    ----------
    estimator : str, class or Block
        ``"module:Class"``, a class (built as ``Class(period=period, q0=q0)``), or an instance
        (its ``period`` set to ``period``).
    period : int
        The IMU's period (macro steps).
    q0 : (4,) array, optional
        The vehicle's initial attitude (body to NED, scalar first).
    available : sequence of str
        The inputs the scenario can wire.

    Returns
    -------
    quadcosim.orchestrator.Block
        Named ``Quaternion_estim``.

    Raises
    ------
    ValueError
        Not a block, a missing output, an input the scenario cannot wire, or a constructor that
        refuses ``period`` and ``q0``.
    """
    if isinstance(estimator, str):
        estimator = load(estimator)
    if isinstance(estimator, type):
        if not issubclass(estimator, Block):
            raise ValueError(f"estimator {label(estimator)} is not an quadcosim.orchestrator.Block; subclass "
                             "quadcosim.estimators.contract.AttitudeEstimator (see its docstring)")
        arguments = _arguments(estimator, {"name": "Quaternion_estim", "period": int(period),
                                           "q0": None if q0 is None else np.asarray(q0, dtype=float)})
        try:
            block = estimator(**arguments)
        except TypeError as error:
            raise ValueError(f"estimator {label(estimator)}: the scenario builds it as Class(period=..., q0=...) "
                             f"and that failed: {error}. Accept both keywords (AttitudeEstimator does).") from error
    else:
        block = estimator
        if not isinstance(block, Block):
            raise ValueError(f"estimator {block!r} is not an quadcosim.orchestrator.Block")
        block.period = int(period)
        if isinstance(block, AttitudeEstimator) and block.q0 is None and q0 is not None:
            block.q0 = _unit_quaternion(q0)
    check(block, available)
    block.name = "Quaternion_estim"
    _guard(block)
    return block


#: How far from 1 the norm of ``q_est`` may drift before the run is stopped (the contract: unit norm).
NORM_TOLERANCE = 1e-3


class ContractBroken(UsageError, ValueError):
    """An estimator's output broke the contract while the run went (a NaN, a quaternion off
    unit norm); the message names the output, the time and the value."""

    names_its_block = True  # the message says which estimator: no frame to add


def _guard(block: Block) -> None:
    """Check the contract at every step of ``block`` while the run goes: every required output
    finite, ``q_est`` of unit norm (within :data:`NORM_TOLERANCE`). A filter that lets ``q``
    grow would otherwise fly on, its run ``completed``, its angles meaningless."""
    if getattr(block.step, "contract_guard", False):
        return
    inner = block.step
    at = [list(block.outputs).index(name) for name in REQUIRED]
    quaternion = at[Q]

    def step(t, u, y):
        inner(t, u, y)
        values = y[at]
        if not np.isfinite(values).all():
            bad = REQUIRED[int(np.flatnonzero(~np.isfinite(values))[0])]
            raise ContractBroken(f"estimator {label(block)}: {bad} = {y[at[REQUIRED.index(bad)]]} at t = {t:.4f} s; "
                                 "every output must be a finite number at every step (estimators/contract.py)")
        norm = float(np.sqrt(np.dot(y[quaternion], y[quaternion])))
        if abs(norm - 1.0) > NORM_TOLERANCE:
            raise ContractBroken(f"estimator {label(block)}: |q_est| = {norm:.6g} at t = {t:.4f} s; the contract "
                                 f"asks for a unit quaternion (within {NORM_TOLERANCE:g}): normalise q in update")

    step.contract_guard = True
    block.step = step


def _arguments(cls, offered: dict) -> dict:
    """The keywords of ``offered`` that ``cls``'s constructor takes (all, with ``**kwargs``);
    ``name`` only where it has no default (a plain :class:`quadcosim.orchestrator.Block`)."""
    try:
        parameters = inspect.signature(cls).parameters
    except (TypeError, ValueError):
        return {k: v for k, v in offered.items() if k != "name"}
    if any(p.kind is p.VAR_KEYWORD for p in parameters.values()):
        return {k: v for k, v in offered.items() if k != "name" or parameters.get("name", None) is not None}
    taken = {k: v for k, v in offered.items() if k in parameters}
    if "name" in taken and parameters["name"].default is not inspect.Parameter.empty:
        del taken["name"]
    return taken


def check(block, available=INPUTS) -> None:
    """Refuse a block that breaks the contract, naming what is missing.

    Parameters
    ----------
    block : quadcosim.orchestrator.Block
        The estimator.
    available : sequence of str
        The inputs the scenario can wire.

    Raises
    ------
    ValueError
        A required output is missing, or an input is not one the scenario wires.
    """
    missing = [y for y in REQUIRED if y not in block.outputs]
    if missing:
        raise ValueError(f"estimator {label(block)} lacks the outputs {', '.join(missing)}; an estimator gives "
                         f"{', '.join(REQUIRED)} (see estimators/contract.py)")
    unknown = [u for u in block.inputs if u not in available]
    if unknown:
        raise ValueError(f"estimator {label(block)} has inputs {', '.join(unknown)} that the scenario cannot wire; "
                         f"its inputs are among {', '.join(available)}")
