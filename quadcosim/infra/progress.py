"""What a long command shows while it works, on standard error.

- A run's progress (:class:`Progress`, in simulated seconds): a bar on a terminal, redrawn in
  place and ended at 100 % with a newline when the run completes; to a pipe or a file, a few
  plain lines (when the loop runs, then every quarter of the run), never carriage returns.
- Status lines (:func:`status`) for the phases around a run (set-up, saving, the report), so
  that the screen is never blank for long. They are printed only inside :func:`reporting`
  (the command line turns it on), so that library calls and tests stay quiet.
"""

from __future__ import annotations

import contextlib
import sys
import time

#: Plain lines a run writes to a pipe: one when the loop has run its first chunk, then one at
#: each quarter of the simulated time.
PIPE_LINES = 4

_state = {"on": False, "started": 0.0, "stream": None, "bar": None}


@contextlib.contextmanager
def reporting(on: bool = True, stream=None):
    """Print status lines (:func:`status`) inside this context.

    Parameters
    ----------
    on : bool
        False keeps everything quiet (the context then changes nothing).
    stream : file, optional
        Where to write; standard error by default.
    """
    saved = dict(_state)
    if on:
        _state.update(on=True, started=time.perf_counter(), stream=stream)
    try:
        yield
    finally:
        _state.update(saved)


def active() -> bool:
    """Whether status lines are printed (inside :func:`reporting`)."""
    return _state["on"]


def _stream():
    return _state["stream"] or sys.stderr


def say(text: str, stream=None) -> None:
    """Print ``text`` as a line of its own on ``stream`` (standard error by default): above a
    progress bar being drawn there, never inside it (the bar is redrawn below the line).

    Parameters
    ----------
    text : str
        One line, without its newline.
    stream : file, optional
        Where to write; the stream of :func:`reporting`, or standard error.
    """
    stream = stream or _stream()
    bar, drawn_on = _state["bar"] or (None, None)
    if bar is not None and drawn_on is stream:
        bar.write(text, file=stream)  # clears the bar's line, writes, redraws the bar
    else:
        print(text, file=stream, flush=True)


def status(text: str) -> None:
    """Print one short status line, ``[  2.1 s] text``, with the wall time since
    :func:`reporting` began; nothing outside it (:func:`say` writes it, above a bar)."""
    if _state["on"]:
        say(f"[{time.perf_counter() - _state['started']:5.1f} s] {text}")


class Every:
    """A status line at most every ``seconds`` of wall time, for a long step without a bar.

    Parameters
    ----------
    seconds : float
        Wall time between two lines (s).
    """

    def __init__(self, seconds: float):
        self.seconds, self.last = seconds, time.perf_counter()

    def status(self, text) -> None:
        """Print ``text()`` (a callable, evaluated only when printed) if ``seconds`` have passed,
        on a terminal only: a pipe or a log file gets the phases, not a line every few seconds."""
        if _state["on"] and time.perf_counter() - self.last >= self.seconds and _is_terminal(_stream()):
            status(text())
            self.last = time.perf_counter()


class Progress:
    """Progress of a run: ``update(seconds)`` as the simulated time advances.

    On a terminal, a bar redrawn in place; :meth:`complete` takes it to 100 %, :meth:`close`
    ends its line. Elsewhere (a pipe, a file) plain lines: one at the first update (the loop
    runs), then one each time the run crosses a quarter (:data:`PIPE_LINES`), the last at 100 %;
    each line's percentage is the simulated time reached (an update that crosses several
    quarters prints one line).

    Parameters
    ----------
    total : float
        Simulated time of the run (s).
    label : str
        What runs, at the start of each line.
    stream : file, optional
        Standard error by default.
    """

    def __init__(self, total: float, label: str = "run", stream=None):
        self.total, self.label, self.n = float(total), label, 0.0
        self.stream = stream or _stream()
        self.started = time.perf_counter()
        self.bar = None
        self.next_line = 0
        if _is_terminal(self.stream):
            from tqdm import tqdm

            self.bar = tqdm(total=self.total, file=self.stream, desc=label, unit="s sim", dynamic_ncols=True,
                            bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.1f}/{total:.1f} s "
                                       "[{elapsed}<{remaining}]")
            _state["bar"] = (self.bar, self.stream)

    def update(self, seconds: float) -> None:
        """Advance by ``seconds`` of simulated time (s)."""
        self.n = min(self.total, self.n + seconds)
        if self.bar is not None:
            self.bar.update(self.n - self.bar.n)
            return
        passed = 0  # quarters of the run reached by now (a chunk may cross several at once)
        while passed < PIPE_LINES and self.n >= self.total * (passed + 1) / PIPE_LINES - 1e-9:
            passed += 1
        if self.next_line == 0 or passed >= self.next_line:
            elapsed = time.perf_counter() - self.started
            # one line, whose percentage is the simulated time reached, however many quarters it crossed
            print(f"{self.label}: {int(100 * self.n / self.total):3d} % ({self.n:.1f}/{self.total:g} s simulated, "
                  f"{elapsed:.1f} s)", file=self.stream, flush=True)
            self.next_line = passed + 1

    def complete(self) -> None:
        """The run reached its end: show 100 %."""
        self.update(self.total - self.n)

    def close(self) -> None:
        """End the bar's line (after a failure, at the fraction reached)."""
        if self.bar is not None:
            if (_state["bar"] or (None,))[0] is self.bar:
                _state["bar"] = None
            self.bar.close()
            self.bar = None


def _is_terminal(stream) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False
