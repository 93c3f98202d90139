"""FMU instances kept between runs of one process and reset rather than instantiated again.

A sweep worker runs many members of one scenario: instantiating the same FMUs for each costs
more than some members' stepping. With reuse on (:func:`reuse`, which each sweep worker turns
on), a run's FMU blocks take an idle instance of their model, reset it (``fmi2Reset``, then the
usual set-up and initialization: :meth:`orchestrator.fmu.FMUInstance.reset`) and give it back
when the run ends. The FMUs' reset reproduces a fresh instance bit for bit, which
``tests/test_fmu_reset.py`` checks model by model and on whole runs. With reuse off (the
default) every run instantiates its FMUs and frees them at its end.
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


def acquire(model: str, parameters: dict | None = None, name: str | None = None, start_time: float = 0.0):
    """An initialized instance of ``model``: an idle one reset, when reuse is on and one is
    idle, else a new one. The arguments are those of :class:`orchestrator.fmu.FMUInstance`.

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

    Returns
    -------
    orchestrator.fmu.FMUInstance
    """
    from orchestrator.fmu import FMUInstance, fmu_file

    if _enabled:
        path = fmu_file(model)
        with _lock:
            stack = _idle.get(_key(path))
            instance = stack.pop() if stack else None
        if instance is not None:
            instance.reset(parameters, name=name, start_time=start_time)
            return instance
    return FMUInstance(model, parameters, name=name, start_time=start_time)


def release(instance) -> None:
    """Give back an instance after a run: kept idle when reuse is on, else freed.

    Parameters
    ----------
    instance : orchestrator.fmu.FMUInstance
    """
    if not _enabled or instance.closed:
        instance.close()
        return
    with _lock:
        _idle.setdefault(_key(instance.path), []).append(instance)


def idle_count() -> int:
    """Instances kept idle in this process."""
    with _lock:
        return sum(len(stack) for stack in _idle.values())
