"""Silences of a command: the longest wait between two lines of its output, read from pipes.

``python -m quadcosim.benchmarks.gaps [--show] -- quadcosim run tp --set duration=20 --out /tmp/tp --overwrite``

The command runs in a child process with its standard output and error piped; every line (or
carriage-return redraw) is stamped with the wall time since the start. Printed: the number of
lines on each stream, the longest gap and what came before it, the wait for the first line and
after the last one (the interpreter's exit). ``--show`` prints every stamped line too.
"""

from __future__ import annotations

import argparse
import os
import selectors
import subprocess
import time


def stamped_lines(command: list[str]) -> tuple[list[tuple[float, str, str]], float, int]:
    """Run ``command``; its output lines with their times.

    Parameters
    ----------
    command : list of str
        The command and its arguments.

    Returns
    -------
    lines : list of (float, str, str)
        Wall time since the start (s), stream (``"out"`` or ``"err"``), text, in order of arrival.
    end : float
        Wall time at which the command exited (s).
    code : int
        Its exit code.
    """
    start = time.monotonic()
    child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    selector = selectors.DefaultSelector()
    selector.register(child.stdout, selectors.EVENT_READ, "out")
    selector.register(child.stderr, selectors.EVENT_READ, "err")
    pending, lines, open_streams = {"out": b"", "err": b""}, [], 2
    while open_streams:
        for key, _ in selector.select():
            data = os.read(key.fileobj.fileno(), 65536)
            if not data:
                selector.unregister(key.fileobj)
                open_streams -= 1
                continue
            pending[key.data] += data.replace(b"\r", b"\n")
            *complete, pending[key.data] = pending[key.data].split(b"\n")
            now = time.monotonic() - start
            lines += [(now, key.data, line.decode(errors="replace")) for line in complete]
    code = child.wait()
    return lines, time.monotonic() - start, code


def main(argv=None) -> int:
    """Command line (see the module docstring).

    Parameters
    ----------
    argv : list of str, optional
        The arguments (the process's if None).

    Returns
    -------
    int
        The timed command's exit code.
    """
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--show", action="store_true", help="print every stamped line")
    parser.add_argument("command", nargs=argparse.REMAINDER, help="the command, after --")
    args = parser.parse_args(argv)
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("give the command to time after --")
    lines, end, code = stamped_lines(command)
    if args.show:
        for t, stream, text in lines:
            print(f"{t:8.2f} {stream} {text[:140]}")
    times = [0.0, *(t for t, _, _ in lines), end]
    gaps = [(times[i + 1] - times[i], i) for i in range(len(times) - 1)]
    longest, index = max(gaps)
    before = lines[index - 1][2][:100] if index > 0 else "(the start)"
    counts = {s: sum(1 for _, stream, _ in lines if stream == s) for s in ("out", "err")}
    print(f"exit {code} after {end:.2f} s; lines: {counts['out']} on stdout, {counts['err']} on stderr; "
          f"longest gap {longest:.2f} s, after: {before}; first line after {gaps[0][0]:.2f} s, "
          f"exit {gaps[-1][0]:.2f} s after the last")
    return code


if __name__ == "__main__":  # the same as quadcosim bench gaps
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim bench gaps").run, main)
