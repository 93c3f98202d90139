"""Peak memory of ``quadcosim run tp`` against duration, with and without decimation.

``python -m quadcosim.benchmarks.memory [--durations 20 200 600] [--decimations 1 10] [--json]``

Each case runs the command line in a child process and reads the child's peak resident set
(``wait4``). The bytes recorded are ``samples x (signals + 1) x 8`` (the signals and the time
vector, float64), read back from the saved results. Memory that does not depend on the
duration (the interpreter, NumPy, fmpy, the FMUs, matplotlib) is the same in every case of one
decimation, so the figure of merit is the growth: between the shortest and each longer run,
the peak grows by ``growth`` times the growth of the bytes recorded (1.0: the record is all
that grows).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np


def peak_rss(command: list[str]) -> int:
    """Peak resident set (bytes) of ``command`` run to completion in a child process."""
    child = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(child.pid, 0)
    child.returncode = os.waitstatus_to_exitcode(status)
    if child.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed ({child.returncode}): {child.stderr.read().decode()[-2000:]}")
    child.stderr.close()
    return usage.ru_maxrss * 1024


def measure(duration: float, decimation: int, folder: Path) -> dict:
    """Peak RSS and recorded bytes of one ``tp`` run of ``duration`` s recording every
    ``decimation``-th step, with its results written under ``folder``."""
    out = folder / f"tp-{duration:g}-{decimation}"
    command = [sys.executable, "-m", "quadcosim.main", "run", "tp", "--set", f"duration={duration}",
               "--decimation", str(decimation), "--out", str(out), "--format", "npz", "--overwrite"]
    peak = peak_rss(command)
    with np.load(out / "results.npz") as saved:
        signals = len(json.loads(str(saved["_meta"]))["names"]) + 1  # vectors are stored as one array; + time
        samples = len(saved["time"])
    return {"duration_s": duration, "decimation": decimation, "samples": samples, "signals": signals - 1,
            "recorded_bytes": samples * signals * 8, "peak_rss_bytes": peak}


def main(argv=None) -> int:
    """Run the cases given on the command line and print one line (or a JSON list) for each.
    ``argv``: the arguments (default ``sys.argv[1:]``)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--durations", type=float, nargs="+", default=[20.0, 200.0, 600.0])
    parser.add_argument("--decimations", type=int, nargs="+", default=[1, 10])
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for decimation in args.decimations:
            cases = [measure(d, decimation, Path(folder)) for d in sorted(args.durations)]
            base = cases[0]
            for case in cases:
                recorded = case["recorded_bytes"] - base["recorded_bytes"]
                case["growth"] = (case["peak_rss_bytes"] - base["peak_rss_bytes"]) / recorded if recorded else None
                rows.append(case)
                if not args.json:
                    growth = "" if case["growth"] is None else f"   peak growth / recorded growth {case['growth']:.3f}"
                    print(f"tp {case['duration_s']:6g} s, decimation {decimation:2d}: {case['samples']:7d} samples x "
                          f"{case['signals']} signals, recorded {case['recorded_bytes'] / 1e6:7.1f} MB, "
                          f"peak RSS {case['peak_rss_bytes'] / 1e6:7.1f} MB{growth}", flush=True)
    if args.json:
        print(json.dumps(rows))
    return 0


if __name__ == "__main__":  # the same as quadcosim bench memory
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim bench memory").run, main)
