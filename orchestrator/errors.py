"""The errors of the master."""

from __future__ import annotations

from quadcosim.orchestrator.result import Result

from quadcosim.infra.errors import RunError, UsageError


class SimulationError(RunError, RuntimeError):
    """A run failed.

    Parameters
    ----------
    message : str
        What failed, where and when.
    result : quadcosim.orchestrator.Result, optional
        What was recorded up to the failure.
    """

    def __init__(self, message: str, result: Result | None = None):
        super().__init__(message)
        self.result = result


class RunInterrupted(SimulationError):
    """The run was interrupted (Ctrl-C, or SIGTERM turned into
    :class:`quadcosim.infra.interrupts.Terminated`).

    Parameters
    ----------
    message : str
        When it stopped.
    result : quadcosim.orchestrator.Result or None
        What was recorded.
    signal_number : int
        The signal that stopped it.
    """

    def __init__(self, message: str, result: Result | None, signal_number: int):
        super().__init__(message, result)
        self.signal_number = signal_number

    @property
    def exit_code(self) -> int:
        """The command line's exit code: 128 + the signal, as a process that signal ended."""
        return 128 + self.signal_number


class AlgebraicLoopError(UsageError, ValueError):
    """Blocks with direct feedthrough form a cycle."""

    def __init__(self, cycle: list[str]):
        self.cycle = cycle
        super().__init__(
            "algebraic loop: " + " -> ".join(cycle + cycle[:1]) + ". Every block in it passes its inputs "
            "straight to its outputs. Break it with a block without direct feedthrough (a delay, a "
            "filter state) or connect one of these signals from elsewhere."
        )
