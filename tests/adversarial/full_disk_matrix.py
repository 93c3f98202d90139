"""A disk that fills at every phase of ``calibrate``, ``run``, ``run --stream`` and ``log replay``.

Each command runs once on a roomy folder, which measures the bytes it writes; then on tmpfs
disks that hold only a share of them (:data:`SHARES`, 36 runs from 0 % to 105 %: the disk fills
before the folder is made, while the record, the figures, the diagram or the parameter files are written, or while
``metrics.json`` itself is). Every run must leave its ``metrics.json`` (``log replay``: its JSON
file) or nothing, and no temporary, empty or partial file under a final name: each PNG ends with
its ``IEND`` chunk, each JSON parses, each record loads, each parameter file reads.

``python tests/adversarial/full_disk_matrix.py`` (as root: it mounts tmpfs) prints one line per
run and a table, and exits 1 when a run broke the rule. ``tests/adversarial/test_full_disk_matrix.py``
runs a few of these cases in CI.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: shares of what each command writes that its disk holds: 36 runs. ``log replay`` writes one JSON
#: file of a few kB (it fits or it does not); the others write megabytes in phases.
SHARES = {"calibrate": (0.0, 0.2, 0.3, 0.31, 0.33, 0.36, 0.42, 0.5, 0.7, 0.9, 1.05),
          "run": (0.0, 0.5, 0.6, 0.65, 0.7, 0.75, 0.8, 0.9, 1.0, 1.05),
          "run --stream": (0.0, 0.6, 0.7, 0.75, 0.8, 0.83, 0.86, 0.9, 0.95, 1.0, 1.05),
          "log replay": (0.0, 0.5, 1.0, 2.0)}
PAGE = 4096
TIMEOUT_S = 300

#: name: the command line with ``{log}`` and ``{out}`` to fill in; ``{out}`` is the output
#: folder (``log replay`` writes ``{out}/replay.json`` into it, made empty beforehand)
COMMANDS = {
    "calibrate": ["calibrate", "{log}", "--out", "{out}", "--models", "current", "throttle"],
    "run": ["run", "tp", "--set", "duration=0.5", "--out", "{out}"],
    "run --stream": ["run", "tp", "--set", "duration=0.5", "--stream", "--out", "{out}"],
    "log replay": ["log", "replay", "{log}", "--json", "{out}/replay.json"],
}


@contextlib.contextmanager
def tmpfs(folder: Path, size: int):
    """A tmpfs at ``folder`` with ``size`` bytes free (rounded down to whole pages; a page-sized
    disk made full when ``size`` is under a page) while the block runs; a filler file named
    ``filler`` holds the rest."""
    folder.mkdir(parents=True, exist_ok=True)
    pages = size // PAGE
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={max(1, pages) * PAGE}", "tmpfs", str(folder)],
                          capture_output=True)
    if done.returncode != 0:
        raise PermissionError(f"cannot mount a tmpfs at {folder}: {done.stderr.decode().strip()}")
    try:
        if pages == 0:
            (folder / "filler").write_bytes(bytes(PAGE))
        yield folder
    finally:
        subprocess.run(["umount", str(folder)], check=True)


def command_line(name: str, log: Path, out: Path) -> list[str]:
    return [sys.executable, "-m", "quadcosim.main", *(a.format(log=log, out=out) for a in COMMANDS[name])]


def invoke(name: str, log: Path, out: Path) -> tuple[int, str, float]:
    """Run command ``name``; (exit code, stderr, seconds). A folder ``log replay`` writes into is made first."""
    if name == "log replay":
        out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    try:
        done = subprocess.run(command_line(name, log, out), capture_output=True, text=True, timeout=TIMEOUT_S,
                              cwd=ROOT, env=os.environ | {"MPLBACKEND": "Agg"})
    except subprocess.TimeoutExpired:
        return -1, "hang: killed after the timeout", time.perf_counter() - started
    return done.returncode, done.stderr, time.perf_counter() - started


def written_bytes(folder: Path) -> int:
    """Bytes the files under ``folder`` take on a page-granular filesystem."""
    return sum(-(-(p.stat().st_size) // PAGE) * PAGE for p in folder.rglob("*") if p.is_file())


def _whole(path: Path) -> str:
    """Why the file at ``path`` is not whole (empty when it is)."""
    data = path.read_bytes()
    if not data:
        return "empty"
    if path.suffix == ".png" and not (data[:8] == b"\x89PNG\r\n\x1a\n" and data[-8:-4] == b"IEND"):
        return "a PNG without its end"
    if path.suffix == ".json":
        try:
            json.loads(data)
        except ValueError as error:
            return f"JSON that does not parse ({error})"
    if path.suffix in (".parm", ".params"):
        from quadcosim.calibration.flight.autopilot import read_parameters

        try:
            read_parameters(path)
        except ValueError as error:
            return f"unreadable parameters ({error})"
    if path.suffix == ".npy":
        import numpy as np

        try:
            np.load(path)
        except Exception as error:  # noqa: BLE001 - any failure to load is the finding
            return f"a chunk that does not load ({type(error).__name__})"
    return ""


def check(name: str, out: Path, disk: Path) -> tuple[str, list[str]]:
    """(what the run left, what breaks the rule) for command ``name`` writing into ``out`` on ``disk``."""
    problems = []
    for path in disk.rglob("*"):
        if path.is_file() and path.name != "filler":
            if path.name.startswith(".") or ".part" in path.name:
                problems.append(f"temporary left: {path.relative_to(disk)}")
            elif (why := _whole(path)):
                problems.append(f"{path.relative_to(disk)}: {why}")
    names = sorted(p.name for p in out.iterdir()) if out.is_dir() else []
    if not names:
        return "nothing", problems
    if name == "log replay":
        return ("replay.json" if names == ["replay.json"] else f"files {names}"), problems
    if "metrics.json" not in names:
        return f"no metrics.json beside {names}", [*problems, f"{names} without metrics.json"]
    try:
        metrics = json.loads((out / "metrics.json").read_text())
    except ValueError:
        return "a broken metrics.json", problems
    listed = metrics.get("files", [])
    missing = [f for f in listed if not (out / f).exists()]
    unlisted = [n for n in names if n not in listed and n != "metrics.json"]
    if missing:
        problems.append(f"listed but absent: {missing}")
    if unlisted:
        problems.append(f"present but not listed: {unlisted}")
    if name.startswith("run") and {"results.npz", "results.stream"} & set(listed):
        try:  # a record metrics.json lists must load (one it says was not written is absent)
            from quadcosim.orchestrator import Result

            Result.load(out)
        except Exception as error:  # noqa: BLE001 - a record that does not load is the finding
            problems.append(f"record does not load ({type(error).__name__}: {error})")
    status = metrics.get("status", "?")
    during = metrics.get("stopped_during") or ", ".join(metrics.get("files_not_written", {})) or ""
    return f"metrics.json ({status}{'; ' + during if during and status != 'completed' else ''})", problems


def one(name: str, log: Path, work: Path, budget: int | None) -> dict:
    """Run ``name`` on a tmpfs of ``budget`` bytes (None: a plain folder) and check what it left."""
    disk = work / "disk"
    if disk.exists():
        shutil.rmtree(disk)
    out = disk / "out"
    with tmpfs(disk, budget) if budget is not None else contextlib.nullcontext(disk.mkdir(parents=True)):
        code, err, seconds = invoke(name, log, out)
        left, problems = check(name, out, disk)
        size = written_bytes(disk)
    if "Traceback" in err:
        problems.append("traceback: " + err.strip().splitlines()[-1])
    if code == -1:
        problems.append("hang")
    if code not in (0, 1, 2, -1):
        problems.append(f"exit {code}")
    last = next((line for line in reversed(err.strip().splitlines()) if line.strip()), "")
    return {"command": name, "budget": budget, "exit": code, "left": left, "problems": problems,
            "seconds": round(seconds, 1), "bytes": size, "said": last[:160]}


def synthetic_log(work: Path) -> Path:
    sys.path.insert(0, str(ROOT))
    from tests.flightlog_synthetic import write_log

    log = work / "flight.log"
    write_log(log, duration=20.0)
    return log


def needed_bytes(name: str, written: int) -> int:
    """What command ``name`` needs free to finish, from the bytes it ``written`` unhindered: the
    room a run or a calibration keeps for its ``metrics.json`` besides (64 kB), and the
    temporary file of the largest output beside its final one is within the shares' top."""
    return written + (0 if name == "log replay" else 64 * 1024)


def main(argv=None) -> int:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--log", help="the flight log of calibrate and log replay (default: a synthetic one)")
    parser.add_argument("--commands", default=",".join(COMMANDS), help="comma-separated commands")
    parser.add_argument("--json", help="write the outcomes here")
    args = parser.parse_args(argv)
    outcomes = []
    with tempfile.TemporaryDirectory() as folder:
        work = Path(folder)
        log = Path(args.log).resolve() if args.log else synthetic_log(work)
        for name in args.commands.split(","):
            measured = one(name, log, work, None)
            needed = needed_bytes(name, measured["bytes"])
            print(f"{name}: writes {measured['bytes']} bytes unhindered (exit {measured['exit']}, "
                  f"{measured['seconds']} s)", flush=True)
            for share in SHARES[name]:
                budget = int(share * needed)
                found = one(name, log, work, budget) | {"share": share}
                outcomes.append(found)
                print(f"  {share:6.1%} {budget:8d} B exit {found['exit']} {found['seconds']:5.1f} s  {found['left']}"
                      f"{'  PROBLEMS ' + '; '.join(found['problems']) if found['problems'] else ''}", flush=True)
    print("\n| command | disk (share of what it writes) | exit | left | rule |\n|---|---|---|---|---|")
    for o in outcomes:
        print(f"| {o['command']} | {o['budget'] / 1024:.0f} kB ({o['share']:.1%}) | {o['exit']} | {o['left']} | "
              f"{'broken: ' + '; '.join(o['problems']) if o['problems'] else 'kept'} |")
    broken = sum(bool(o["problems"]) for o in outcomes)
    print(f"\n{len(outcomes)} runs, {broken} broke the rule")
    if args.json:
        from quadcosim.infra.files import write_json

        write_json(args.json, outcomes)
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())
