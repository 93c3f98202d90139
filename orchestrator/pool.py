"""FMU instances kept between runs of one process and reset rather than instantiated again.

A sweep worker runs many members of one scenario: instantiating the same FMUs for each costs
more than some members' stepping. With reuse on (:func:`reuse`, which each sweep worker turns
on), a run's FMU blocks take an idle instance of their model, reset it (``fmi2Reset``, then the
usual set-up and initialization: :meth:`quadcosim.orchestrator.fmu.FMUInstance.reset`) and give it back
when the run ends. The project's FMUs' reset reproduces a fresh instance bit for bit, which
``tests/test_fmu_reset.py`` checks model by model and on whole runs. Any other FMU is pooled
only once this process has seen its reset do so (:func:`_reset_verified`); one whose reset does
not (a reset that resets nothing, or fails) is instantiated afresh for every run, and a warning
says so once. With reuse off (the default) every run instantiates its FMUs and frees them at
its end.
"""

from __future__ import annotations

import threading

_idle: dict[tuple, list] = {}  # (FMU file, modification time) -> idle instances
_lock = threading.Lock()
_enabled = False


def reuse(enabled: bool = True, free: bool = True) -> bool:
    """Turn the reuse of FMU instances in this process on or off; returns the previous state.
    Turning it off frees the idle instances, unless ``free`` is False.

    Parameters
    ----------
    enabled : bool
        Keep instances between runs.
    free : bool
        With ``enabled`` False: free the idle instances. False keeps them for a later
        ``reuse(True)`` (the pytest plugin's fixtures turn reuse on for their own tests alone,
        and keep the instances for the next such test of the session).
    """
    global _enabled
    previous, _enabled = _enabled, bool(enabled)
    if not _enabled and free:
        with _lock:
            idle = [instance for stack in _idle.values() for instance in stack]
            _idle.clear()
        for instance in idle:
            instance.close()
    return previous


def _key(path) -> tuple:
    return str(path), path.stat().st_mtime_ns


def acquire(model: str, parameters: dict | None = None, name: str | None = None, start_time: float = 0.0,
            isolated: bool | None = None):
    """An initialized instance of ``model``: an idle one reset, when reuse is on and one is
    idle, else a new one. The arguments are those of :class:`quadcosim.orchestrator.fmu.FMUInstance`.

    Parameters
    ----------
    model : str
        Built FMU name or ``.fmu`` path.
    parameters : dict, optional
        Parameter overrides, by variable name.
    name : str, optional
        Instance (block) name used in messages.
    start_time : float
        Start time (s).
    isolated : bool, optional
        In a worker process or not; by default :func:`quadcosim.orchestrator.isolated.runs_isolated` decides.

    Returns
    -------
    quadcosim.orchestrator.fmu.FMUInstance
    """
    from quadcosim.orchestrator.fmu import fmu_file
    from quadcosim.orchestrator.isolated import open_instance

    if _enabled:
        path = fmu_file(model)
        if not _reset_verified(path, parameters, name, start_time):
            return open_instance(model, parameters, name=name, start_time=start_time, isolated=isolated)
        with _lock:
            stack = _idle.get(_key(path))
            instance = stack.pop() if stack else None
        if instance is not None:
            instance.reset(parameters, name=name, start_time=start_time)
            return instance
    return open_instance(model, parameters, name=name, start_time=start_time, isolated=isolated)


#: The step of the reset check (s), and the number of steps that move the state before the reset.
CHECK_STEP, CHECK_STEPS = 1e-3, 10
_verified: dict[tuple, bool] = {}


def _reset_verified(path, parameters, name, start_time) -> bool:
    """Whether the reset of the FMU at ``path`` makes an instance that steps as a fresh one.

    The project's own FMUs are checked by ``tests/test_fmu_reset.py``. Any other is checked once
    per process: one instance steps once from its start; another is driven (every input
    at 0.5) for :data:`CHECK_STEPS` steps, reset, and steps once. Its outputs must equal the
    first's, bit for bit. An FMU that fails is never pooled (a fresh instance for every run),
    which a warning says once.
    """
    import warnings

    import numpy as np
    from quadcosim.orchestrator.isolated import is_own, open_instance

    key = _key(path)
    if key in _verified:
        return _verified[key]
    if is_own(path):
        _verified[key] = True
        return True
    fresh = driven = None
    reason = None
    try:
        fresh = open_instance(path, parameters, name=name, start_time=start_time)
        outputs, inputs = list(fresh.outputs), list(fresh.inputs)
        fresh.step(start_time, CHECK_STEP)
        expected = fresh.get(outputs)
        driven = open_instance(path, parameters, name=name, start_time=start_time)
        if inputs:
            driven.set(inputs, np.full(len(inputs), 0.5))
        for k in range(CHECK_STEPS):
            driven.step(start_time + k * CHECK_STEP, CHECK_STEP)
        driven.reset(parameters, name=name, start_time=start_time)
        driven.step(start_time, CHECK_STEP)
        got = driven.get(outputs)
        if not np.array_equal(expected, got, equal_nan=True):
            worst = int(np.argmax(np.abs(np.nan_to_num(expected - got, nan=np.inf))))
            reason = (f"after a reset, one step gives {outputs[worst]} = {got[worst]!r} where a fresh instance "
                      f"gives {expected[worst]!r}")
    except Exception as error:  # a reset refused, or a call that fails: not poolable
        reason = f"its reset check failed: {error}".splitlines()[0]
    finally:
        for instance in (fresh, driven):
            if instance is not None:
                instance.close()
    _verified[key] = reason is None
    if reason is not None:
        from quadcosim.orchestrator.fmu import fmi_version

        reset = f"fmi{fmi_version(path)}Reset"
        warnings.warn(f"{path.name}: {reset} does not reproduce a fresh instance ({reason}); each run instantiates "
                      "it afresh instead of reusing a pooled one", RuntimeWarning, stacklevel=3)
    return _verified[key]


def release(instance) -> None:
    """Give back an instance after a run: kept idle when reuse is on and its FMU's reset is
    verified (:func:`_reset_verified`), else freed.

    Parameters
    ----------
    instance : quadcosim.orchestrator.fmu.FMUInstance
    """
    if not _enabled or instance.closed or not _verified.get(_key(instance.path), False):
        instance.close()  # an FMU whose reset is not verified is never kept
        return
    with _lock:
        _idle.setdefault(_key(instance.path), []).append(instance)


def idle_count() -> int:
    """Instances kept idle in this process."""
    with _lock:
        return sum(len(stack) for stack in _idle.values())
