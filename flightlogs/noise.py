"""What the log readers print while they read, captured and summarised in one warning.

pymavlink's fast indexer writes a ``bad header`` line to the process's standard error (from C)
for every byte it skips, and its Python reader a ``Skipped N bad bytes`` line; pyulog prints
its warnings (``File corruption detected``, ``unknown message type``) on standard output. A
corrupt tail of 10 MB is ten million lines. :func:`captured` takes both streams, at the level of
the file descriptors (C output included) and of ``sys.stdout``/``sys.stderr``, while a reader
runs: the lines are counted by kind and the first few kept, in bounded memory, so that the
reading layer can say in one warning what was skipped.
"""

from __future__ import annotations

import contextlib
import ctypes
import json
import os
import re
import subprocess
import sys
import threading
from dataclasses import dataclass, field

#: Lines kept verbatim, the first ones, for the warning.
KEPT_LINES = 3

# (kind, pattern): a line of the readers' output, counted by kind; the number a pattern
# captures (bytes skipped) is summed
_KINDS = (
    ("bad header", re.compile(r"^bad header")),
    ("skipped bytes", re.compile(r"^Skipped (\d+) bad bytes")),
    ("unknown message type", re.compile(r"unknown msg type|unknown message type")),
    ("unparsed message", re.compile(r"^Failed to parse|^bad msg at offset")),
    ("message without its subscription", re.compile(r"no subscription found")),
    ("corruption", re.compile(r"[Cc]orruption detected|Failed to find sync|Found sync")),
)


@dataclass
class Noise:
    """The readers' output while :func:`captured` was active.

    Attributes
    ----------
    lines : int
        Lines printed.
    kinds : dict
        Lines per kind (``bad header``, ``skipped bytes``...), and ``other``.
    skipped_bytes : int
        Bytes the readers said they skipped (a ``bad header`` line is one byte).
    first : list of str
        The first lines, as printed.
    """

    lines: int = 0
    kinds: dict = field(default_factory=dict)
    skipped_bytes: int = 0
    first: list = field(default_factory=list)
    _partial: str = ""
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def feed(self, text: str):
        """Count the complete lines of ``text`` (the rest waits for the next call)."""
        with self._lock:
            body, newline, rest = (self._partial + text).rpartition("\n")
            self._partial = rest
            if not newline:
                return
            lines = body.count("\n") + 1
            if body.count("bad header") == lines and body.startswith("bad header"):  # a run of skipped bytes
                wanted = KEPT_LINES - len(self.first)
                if wanted > 0:
                    self.first += [line[:200] for line in body.split("\n", wanted)[:wanted]]
                self.lines += lines
                self.kinds["bad header"] = self.kinds.get("bad header", 0) + lines
                self.skipped_bytes += lines
                return
            for line in body.split("\n"):
                self._line(line)

    def close(self):
        """Count a last line that did not end with a newline."""
        with self._lock:
            if self._partial:
                self._line(self._partial)
                self._partial = ""

    def _line(self, line: str):
        line = line.strip()
        if not line:
            return
        self.lines += 1
        if len(self.first) < KEPT_LINES:
            self.first.append(line[:200])
        for kind, pattern in _KINDS:
            match = pattern.search(line)
            if match:
                self.kinds[kind] = self.kinds.get(kind, 0) + 1
                if kind == "bad header":
                    self.skipped_bytes += 1
                elif kind == "skipped bytes":
                    self.skipped_bytes += int(match.group(1))
                return
        self.kinds["other"] = self.kinds.get("other", 0) + 1

    def summary(self, reader: str) -> str | None:
        """One warning saying what ``reader`` printed, or None when it printed nothing."""
        if not self.lines:
            return None
        counts = ", ".join(f"{n} {kind}" for kind, n in sorted(self.kinds.items(), key=lambda item: -item[1]))
        skipped = f"; {self.skipped_bytes} bytes skipped" if self.skipped_bytes else ""
        first = " | ".join(self.first)
        return f"{reader} reported {self.lines} problems while reading ({counts}{skipped}); the first: {first}"


class _Writer:
    """A text stream that counts what is written to it (``sys.stdout`` during a capture)."""

    def __init__(self, noise: Noise):
        self.noise = noise

    def write(self, text):
        self.noise.feed(str(text))
        return len(text)

    def flush(self):
        pass

    def isatty(self):
        return False


def _flush_c_streams():
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):
        pass


# The counter of the descriptors' output runs in a process of its own (this file run as a script,
# standard library only): a reader's C code prints while it holds the interpreter's lock, so a
# thread of this process could not drain the pipe, the pipe would fill, and the reader would block
# on it for ever.
def _count_standard_input():
    """The counter's process: count standard input's lines, then print the counts as JSON. A Ctrl-C
    reaches the whole process group: the counter leaves it to its parent and ends with its input."""
    import signal

    for number in (signal.SIGINT, signal.SIGTERM):
        signal.signal(number, signal.SIG_IGN)
    noise = Noise()
    while chunk := sys.stdin.buffer.read1(1 << 16):
        noise.feed(chunk.decode("utf-8", "replace"))
    noise.close()
    json.dump({"lines": noise.lines, "kinds": noise.kinds, "skipped_bytes": noise.skipped_bytes,
               "first": noise.first}, sys.stdout)


def _merge(noise: Noise, counted: dict):
    """Add the counts of the descriptors' output (the counter's) to ``noise`` (Python's writes)."""
    noise.lines += counted.get("lines", 0)
    noise.skipped_bytes += counted.get("skipped_bytes", 0)
    for kind, n in counted.get("kinds", {}).items():
        noise.kinds[kind] = noise.kinds.get(kind, 0) + n
    noise.first = (counted.get("first", []) + noise.first)[:KEPT_LINES]


def _counter():
    """The counting process (its standard input the pipe to count), or None where it cannot start."""
    try:
        return subprocess.Popen([sys.executable, "-I", __file__, "--count"], stdin=subprocess.PIPE,
                                stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    except OSError:
        return None


@contextlib.contextmanager
def captured():
    """Within the block, standard output and error (both file descriptors and Python's streams)
    are counted into the :class:`Noise` yielded instead of being printed.

    Outside the main thread, or where the descriptors cannot be redirected, Python's streams
    alone are captured.

    Yields
    ------
    Noise
    """
    noise = Noise()
    writer = _Writer(noise)
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    counter, saved = None, None
    if threading.current_thread() is threading.main_thread():
        counter = _counter()
    if counter is not None:
        _flush_c_streams()
        saved = (os.dup(1), os.dup(2))
        os.dup2(counter.stdin.fileno(), 1)
        os.dup2(counter.stdin.fileno(), 2)
    try:
        with contextlib.redirect_stdout(writer), contextlib.redirect_stderr(writer):
            yield noise
    finally:
        if counter is not None:
            _flush_c_streams()
            os.dup2(saved[0], 1)  # the pipe's last writers close with the counter's stdin: it sees its end
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])
            try:
                out, _ = counter.communicate(timeout=60)
                _merge(noise, json.loads(out or b"{}"))
            except (ValueError, OSError, subprocess.TimeoutExpired):
                counter.kill()
                counter.wait()
        noise.close()


if __name__ == "__main__" and sys.argv[1:] == ["--count"]:
    _count_standard_input()
