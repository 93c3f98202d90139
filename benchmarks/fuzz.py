"""The long fuzz of the FMUs (``python -m quadcosim.benchmarks.fuzz``), beside the short one of the tests.

Each FMU is driven through its bare FMI functions by ``tests/fuzz_fmu.py`` (hypothesis draws
sessions of calls in random order: value references anywhere in the unsigned range, NaN, Inf
and huge reals, random times and steps, extreme parameters, and calls on an instance after it
was freed, freed twice included), in a child process per model so that a crash is reported
with the call that caused it. Every call must return an FMI status, an OK status must come
with finite outputs, and every call on a freed instance must return fmi2Error. Prints, per
model and in total, the calls made, those on a freed instance, the double frees, the statuses
and the slowest call; exits non-zero when a model fails. It takes minutes: the test suite runs
the same fuzz with a smaller budget (``tests/test_reliability_fmus.py``).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

FUZZER = Path(__file__).resolve().parent.parent / "tests" / "fuzz_fmu.py"
CALLS = 100_000  # per model; the tests make 10,000


def fuzz(model: str, calls: int) -> dict:
    """Fuzz one FMU in a child process.

    Parameters
    ----------
    model : str
        A built FMU (``quadcosim.fmus.MODELS``).
    calls : int
        Calls to make, at least.

    Returns
    -------
    dict
        The fuzzer's summary, and ``failed``: None, or the exit code, the last call made and
        the end of the child's error output.
    """
    with tempfile.TemporaryDirectory() as folder:
        log = Path(folder) / "calls.log"
        done = subprocess.run([sys.executable, str(FUZZER), model, str(calls), str(log)], capture_output=True,
                              text=True, env=os.environ | {"PYTHONHASHSEED": "0"})
        last = log.read_text().splitlines()[-1:] if log.exists() else []
    if done.returncode:
        return {"model": model, "failed": {"code": done.returncode, "last_call": last, "stderr": done.stderr[-2000:]}}
    return json.loads(done.stdout.splitlines()[-1]) | {"failed": None}


def main(argv=None) -> int:
    """Fuzz every FMU; print one line per model and the totals (or one JSON object); returns 0, or
    1 when any model failed. ``argv``: the arguments (default ``sys.argv[1:]``)."""
    import argparse

    from quadcosim.fmus import MODELS

    parser = argparse.ArgumentParser(prog="python -m quadcosim.benchmarks.fuzz", description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=CALLS, help=f"calls per model (default {CALLS:,})")
    parser.add_argument("--models", nargs="+", default=list(MODELS), choices=MODELS)
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    summaries = [fuzz(model, args.calls) for model in args.models]
    totals = Counter()
    for summary in summaries:
        if not summary["failed"]:
            totals.update({key: summary[key] for key in ("calls", "sessions", "calls_after_free", "double_frees")})
    report = {"models": summaries, "totals": dict(totals), "failed": [s["model"] for s in summaries if s["failed"]]}
    if args.json:
        print(json.dumps(report))
    else:
        for s in summaries:
            if s["failed"]:
                print(f"{s['model']}: FAILED (exit {s['failed']['code']}) at {s['failed']['last_call']}\n"
                      f"{s['failed']['stderr']}")
                continue
            print(f"{s['model']}: {s['calls']:,} calls in {s['sessions']:,} sessions, {s['calls_after_free']:,} on a "
                  f"freed instance, {s['double_frees']:,} double frees; statuses {s['statuses']}; slowest call "
                  f"{s['slowest_call_cpu_s'] * 1e3:.1f} ms of CPU ({s['slowest_call']})")
        print(f"total: {totals['calls']:,} calls, {totals['calls_after_free']:,} on a freed instance, "
              f"{totals['double_frees']:,} double frees, {len(report['failed'])} model(s) failed")
    return 1 if report["failed"] else 0


if __name__ == "__main__":  # the same as quadcosim bench fuzz
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim bench fuzz").run, main)
