"""The errors of an FMU's calls, and the log they quote."""

from __future__ import annotations

from collections import deque

from quadcosim.infra.errors import RunError, UsageError

STATUS = ("OK", "Warning", "Discard", "Error", "Fatal", "Pending")
#: A status above any FMI status: an FMI 3.0 FMU asked to end the simulation in ``fmi3DoStep``
#: (``terminateSimulation``), or returned early, which the master does not allow.
TERMINATED = 6


def status_name(status: int) -> str:
    """The name of an FMI status, or the number an FMU returned that is no status at all."""
    return STATUS[status] if 0 <= status < 6 else f"{status} (no FMI status: taken as a failure)"


def failed(status: int) -> bool:
    """Whether an FMI call failed: any status but OK and Warning (-1 is no success, nor is
    :data:`TERMINATED`)."""
    return not 0 <= status <= 1


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

    def keep(self, status: int, message: bytes | None):
        """Keep one message the FMU logged with ``status`` (FMI 2.0 and 3.0 alike)."""
        keep(self, status, message)


def keep(log, status: int, message: bytes | None):
    """Append one message an FMU logged with ``status`` to ``log`` (a deque), counting a warning
    into an :class:`FMULog`."""
    label = STATUS[status] if 0 <= status < 6 else status
    text = f"[{label}] {(message or b'').decode(errors='replace')}"
    log.append(text)
    if status == 1 and isinstance(log, FMULog):
        log.warnings += 1
        if len(log.first_warnings) < log.FIRST:
            log.first_warnings.append(text)


class FMUError(RunError, RuntimeError):
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
        what = (f"returned {status_name(status)}" if status != TERMINATED else
                "asked to end the simulation (terminateSimulation, or an early return the master did not allow)")
        super().__init__(f"{block}: {function} {what}{when}.\n  FMU log:\n  {logged}")


class ParameterRefused(UsageError, FMUError, ValueError):
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
