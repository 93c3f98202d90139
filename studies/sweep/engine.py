"""Running a sweep's members on Dask distributed, streaming their results to disk.

One code path: a :class:`distributed.LocalCluster` of worker processes (one thread each) by
default, or any running scheduler given by its address. Each worker prepares itself once
(:class:`Preload`: imports, FMU extraction, shared libraries loaded); every member then
builds fresh FMU instances from that extraction. Members are deterministic: their seed is
one of their options, so the table does not depend on the number of workers or on which
worker ran what.

On disk, in the sweep folder:

- ``sweep.json``: the scenario and every member's options (what ``--resume`` checks against);
- ``members/NNNNNN/metrics.json``: one member's options, metrics, status, error, wall time,
  written atomically when it finishes; ``error.txt`` holds the traceback of a failure, and the
  member's results and figures are there only when asked (``keep_results``);
- ``sweep.csv`` and ``sweep.parquet``: the table of every finished member, rewritten
  atomically as members finish.

The member folders are the record: ``--resume`` reads them, skips the members that
finished, runs the others (failed ones included) and rewrites the table.
"""

from __future__ import annotations

import contextlib
import json
import logging
import math
import os
import sys
import tempfile
import time
import traceback
import uuid
import warnings
from contextlib import ExitStack
from dataclasses import dataclass, field
from pathlib import Path

from distributed import WorkerPlugin
from quadcosim.studies.sweep import table
from quadcosim.studies.sweep.grid import Member, Plan, stored_members

from quadcosim.infra.errors import UsageError
from quadcosim.infra.files import atomic_path, write_text

#: Keys of a scenario's metrics that are not metrics of a member.
NOT_METRICS = ("scenario", "options", "figures", "units", "injected_faults", "status", "diverged",
               "signals_not_saved")  # a member saves no record unless --results: its own metrics.json says
_members_run = 0  # members run by this process (reported by worker_state)
#: Members submitted ahead per worker, and at least: enough to keep every worker busy while
#: results come back, few enough that neither the client nor the scheduler grows with the plan.
IN_FLIGHT_PER_WORKER, IN_FLIGHT_LEAST = 16, 32


class SweepError(UsageError, ValueError):
    """A sweep cannot start: its folder, its plan or its cluster is not what it should be."""


# ---------------------------------------------------------------------------- on the workers
class Preload(WorkerPlugin):
    """Prepares a worker once for all its members: imports the scenario, extracts every built
    FMU and loads its shared library (fmpy's extraction is cached per process, and a library
    once loaded stays loaded), and records how long that took."""

    name = "quadcosim-preload"

    def __init__(self, scenario: str):
        self.scenario = scenario

    def setup(self, worker):
        started = time.perf_counter()
        import matplotlib

        matplotlib.use("Agg")
        from quadcosim.fmus import MODELS, FMUNotFoundError
        from quadcosim.orchestrator import pool
        from quadcosim.orchestrator.fmu import FMUInstance

        from quadcosim import scenarios

        scenarios.get(self.scenario)
        pool.reuse(True)  # members reset the worker's FMU instances rather than make new ones
        for model in MODELS:
            try:
                FMUInstance(model).close()
            except FMUNotFoundError:
                pass  # a member that needs it will say how to build it
        worker.quadcosim_preload_s = time.perf_counter() - started


def worker_state(dask_worker=None) -> dict:
    """What this worker process has done: members run, FMU extractions, preparation time (s).
    Called through ``Client.run``, which passes the worker as ``dask_worker``."""
    from quadcosim.orchestrator import fmu

    return {"members": _members_run, "extractions": len(fmu._extracted),
            "preload_s": getattr(dask_worker, "quadcosim_preload_s", None)}


def _plain(value):
    """JSON-ready copies of metrics (NumPy scalars and arrays to Python numbers and lists)."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if hasattr(value, "tolist"):
        return _plain(value.tolist())
    return value


def first_non_finite(metrics: dict) -> str | None:
    """Name and value of the first NaN or infinite metric of ``metrics``, if any."""
    for name, value in table.flatten(metrics).items():
        if isinstance(value, float) and not math.isfinite(value):
            return f"{name} = {value}"
    return None


def _resolve(reference: str):
    import importlib

    module, _, name = reference.partition(":")
    return getattr(importlib.import_module(module), name)


def run_member(scenario: str, options: dict, keep_results: bool = False, extra_metrics: str | None = None) -> dict:
    """Run one member where this is called (a Dask worker); never raises for a member's failure.

    Parameters
    ----------
    scenario : str
        Scenario name.
    options : dict
        The member's complete options.
    keep_results : bool
        Also return the files the scenario writes (results, figures), as bytes by name.
    extra_metrics : str, optional
        ``"module:function"`` computing more metrics from ``(result, options)``.

    Returns
    -------
    dict
        ``status`` ("ok", "diverged" or "failed"; ``diverged`` when the flight crossed the
        scenario's bounds, with ``diverged``, the first bound crossed), ``error`` (one line),
        ``warnings`` (one line each), ``traceback``, ``metrics``, ``wall_s`` (s),
        ``cpu_s`` (s of CPU time of the thread that ran the member: a Dask worker's own threads
        are not the member's), ``stepping_cpu_s`` (s of the same thread's CPU time in the
        stepping loop alone), ``worker``, ``files``.
    """
    global _members_run
    from quadcosim import scenarios

    try:
        from distributed import get_worker

        worker = str(get_worker().name)
    except ValueError:
        worker = f"pid {os.getpid()}"
    started, cpu = time.perf_counter(), time.thread_time()
    record = {"status": "ok", "error": None, "traceback": None, "metrics": {}, "files": {}, "warnings": []}
    try:
        # A worker's warnings are the member's: kept in its record, one line each, never printed
        # with a source line on the worker's terminal.
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            if keep_results:
                with tempfile.TemporaryDirectory() as folder:
                    try:
                        result, metrics = scenarios.run(scenario, options, Path(folder))
                    finally:
                        record["files"] = {p.name: p.read_bytes() for p in Path(folder).iterdir() if p.is_file()}
            else:
                result, metrics = scenarios.run(scenario, options)
            record["stepping_cpu_s"] = result.meta.get("loop_cpu_seconds")
            if extra_metrics:
                metrics = metrics | _resolve(extra_metrics)(result, options)
        record["warnings"] = list(dict.fromkeys(" ".join(str(w.message).split()) for w in caught))
        diverged = metrics.get("diverged") if metrics.get("status") == "diverged" else None
        record["metrics"] = _plain({k: v for k, v in metrics.items() if k not in NOT_METRICS})
        bad = first_non_finite(record["metrics"])
        if diverged is not None:  # a crash: its numbers are kept, and never counted as a result
            from quadcosim.scenarios.divergence import message

            record |= {"status": "diverged", "diverged": _plain(diverged),
                       "error": message(scenario, diverged, diverged.get("settings") or [])}
        elif bad:
            record |= {"status": "failed", "error": f"non-finite metric: {bad}"}
    except Exception as error:  # the member failed; the sweep goes on and records why
        record |= {"status": "failed", "error": f"{type(error).__name__}: {error}",
                   "traceback": traceback.format_exc()}
    _members_run += 1
    record["wall_s"] = time.perf_counter() - started
    record["cpu_s"] = time.thread_time() - cpu
    record["worker"] = worker
    return record


# ---------------------------------------------------------------------------- on the client
@dataclass
class Summary:
    """How a sweep went: counts over the whole table, and what this call ran.

    ``out`` is the sweep's folder; ``total``, ``ok``, ``failed`` and ``diverged`` count the
    members of the table by outcome (:data:`quadcosim.studies.sweep.table.OUTCOMES`), ``ran`` and
    ``skipped`` (already done, on --resume) those of this call; ``seconds`` its wall time (s) on
    ``workers`` workers, of which ``startup_s`` and ``shutdown_s`` (s) went to the cluster;
    ``interrupted`` the signal that stopped it (0 if none); ``failures`` and ``divergences`` the
    (member, label, error) of each.
    """

    out: Path
    total: int
    ok: int
    failed: int
    ran: int
    skipped: int
    seconds: float
    workers: int
    startup_s: float = 0.0  # cluster up, workers prepared (s)
    shutdown_s: float = 0.0  # after the last member: cluster closed (s)
    interrupted: int = 0  # the signal that stopped the sweep (SIGINT, SIGTERM), 0 if none
    failures: list = field(default_factory=list)  # (member, label, error)
    diverged: int = 0
    divergences: list = field(default_factory=list)  # (member, label, what crossed)

    @property
    def missing(self) -> int:
        """Members without an outcome: not run, or stopped by an interrupt."""
        return self.total - self.ok - self.failed - self.diverged

    def exit_code(self) -> int:
        """The sweep's exit code (:data:`EXIT_CODES`): 128 + the signal if interrupted, 1 if any
        member failed or is missing, 3 if every member ran but some diverged, 0 if every member
        is ``ok``."""
        if self.interrupted:
            return 128 + self.interrupted
        if self.failed or self.missing:
            return 1
        return 3 if self.diverged else 0

    def counts(self) -> str:
        """The outcomes in one line: ``2 members: 1 ok, 1 diverged, 0 failed``."""
        interrupted = f", {self.missing} interrupted" if self.interrupted and self.missing else \
            f", {self.missing} not run" if self.missing else ""
        return (f"{self.total} member{'s' * (self.total != 1)}: {self.ok} ok, {self.diverged} diverged, "
                f"{self.failed} failed{interrupted}")

    def text(self) -> str:
        """A few lines for a person: counts by outcome, rate, the first failures and divergences,
        where the table is."""
        running = self.seconds - self.startup_s - self.shutdown_s
        rate = self.ran / running if running > 0 else float("nan")
        lines = [self.counts() + f" ({self.ran} run now in {self.seconds:.1f} s on {self.workers} workers:"
                 + f" {self.startup_s:.1f} s to start"
                 + f" them, then {rate:.2f} members/s"
                 + (f", {self.skipped} already done" if self.skipped else "") + ")"]
        for kind, listed, count in (("diverged", self.divergences, self.diverged),
                                    ("failed", self.failures, self.failed)):
            for member, label, error in listed[:5]:
                lines.append(f"  {kind}: member {member} ({label}): {error.splitlines()[0] if error else ''}")
            if count > 5:
                lines.append(f"  ... and {count - 5} more {kind}: see the status and error columns of sweep.csv")
        if self.diverged:
            lines.append("diverged members' numbers describe a crash: they are kept in the table with status "
                         "diverged, never counted as results")
        if self.interrupted:
            lines.append(f"interrupted: finished members are kept; continue with --resume --out {self.out}")
        lines.append(f"table: {self.out / 'sweep.csv'} and sweep.parquet; members in {self.out / 'members'}/")
        return "\n".join(lines)


#: The exit codes of a sweep, by what happened (documented in the sweeps guide).
EXIT_CODES = {0: "every member ok", 1: "a member failed, or was not run", 2: "refused before any member ran",
              3: "every member ran, some diverged", 130: "interrupted (Ctrl-C)", 143: "terminated (SIGTERM)"}


def _write_json(path: Path, data: dict) -> None:
    write_text(path, json.dumps(data, indent=1, default=float) + "\n")


def member_folder(out: Path, index: int) -> Path:
    """The folder of member ``index`` in the sweep folder ``out``."""
    return out / "members" / f"{index:06d}"


def _check_stored(plan: Plan, out: Path, stored: dict, resume: bool) -> None:
    """Refuse a folder whose stored plan is not ``plan`` (or any stored plan, without ``resume``)."""
    count = stored.get("count", len(stored.get("members", ())))
    if not resume:
        finished = len(list((out / "members").glob("*/metrics.json")))
        raise SweepError(f"{out} already holds a sweep of {stored['scenario']} ({count} members, "
                         f"{finished} finished). Continue it with --resume, or choose another --out.")
    if stored["scenario"] != plan.scenario or count != len(plan.members):
        raise SweepError(f"{out} holds a sweep of {stored['scenario']} with {count} members; "
                         f"this one is {plan.scenario} with {len(plan.members)}. Resume with the same grid, "
                         "or choose another --out.")
    # member by member, as JSON reads them back; one at a time, so that memory stays flat
    for old, new in zip(stored_members(stored), plan.members, strict=True):
        now = json.loads(json.dumps(new.options, default=float))
        if old.options != now:
            changed = {k: (old.options.get(k), v) for k, v in now.items() if old.options.get(k) != v}
            raise SweepError(f"{out}: member {new.label or '?'} was run with other options "
                             f"(stored, now: {changed}). Resume with the same grid and --set, "
                             "or choose another --out.")


def _finished_record(path: Path) -> dict | None:
    """A member's ``metrics.json`` as written, or None (with a warning naming the file) when it
    cannot be read: that member runs again."""
    try:
        record = json.loads(path.read_text())
        if not isinstance(record, dict) or record.get("status") not in ("ok", "diverged", "failed"):
            raise ValueError("no status ok, diverged or failed")
        return record
    except (OSError, ValueError) as error:  # JSONDecodeError and UnicodeDecodeError are ValueErrors
        print(f"quadcosim sweep: {path} is unreadable ({error}); that member runs again", file=sys.stderr)
        return None


def _prepare_folder(plan: Plan, out: Path, resume: bool) -> table.Rows:
    """Check the sweep folder against the plan, writing nothing; the table's rows, holding the
    finished members' when resuming (read one at a time, each checked against the plan's member:
    a folder that holds another plan's members is refused)."""
    stored_path = out / "sweep.json"
    if stored_path.exists():
        try:
            stored = json.loads(stored_path.read_text())
        except (OSError, ValueError) as error:
            raise SweepError(f"{stored_path} is unreadable ({error}); choose another --out") from None
        _check_stored(plan, out, stored, resume)
    elif resume:
        raise SweepError(f"{out} holds no sweep to resume (no {stored_path.name}): run the sweep without "
                         "--resume to start it, or give the --out of an earlier sweep.")
    elif any((out / "members").glob("*/metrics.json")):
        raise SweepError(f"{out} holds members of a sweep without its plan (no {stored_path.name}); choose "
                         "another --out.")
    rows = table.Rows(len(plan.members), out)
    if resume:
        for path in sorted((out / "members").glob("*/metrics.json")):
            index = int(path.parent.name) if path.parent.name.isdigit() else -1
            if 0 <= index < len(plan.members) and (record := _finished_record(path)) is not None:
                planned = json.loads(json.dumps(plan.members[index].options, default=float))
                if record.get("options") != planned:
                    rows.close()
                    changed = sorted(k for k in planned.keys() | (record.get("options") or {}).keys()
                                     if planned.get(k) != (record.get("options") or {}).get(k))
                    raise SweepError(f"{path} was run with other options than the plan's member {index} "
                                     f"(differing: {', '.join(changed)}): the folder mixes two sweeps; "
                                     "choose another --out.")
                rows.add(index, table.row(record, plan.varied))
    return rows


def _write_plan(plan: Plan, out: Path) -> None:
    """``sweep.json`` and ``members/``: written once the cluster is up, so that a sweep refused
    before leaves nothing."""
    from quadcosim.studies.sweep import units

    (out / "members").mkdir(exist_ok=True)
    names = list(plan.varied) + (list(plan.members[0].options) if len(plan.members) else [])
    stored = plan.to_json() | {"units": units.of_options(plan.scenario, names)}
    _write_json(out / "sweep.json", json.loads(json.dumps(stored, default=float)))


def _save_member(out: Path, member: Member, record: dict, attempts: int, scenario: str) -> dict:
    folder = member_folder(out, member.index)
    folder.mkdir(parents=True, exist_ok=True)
    for name, data in (record.get("files") or {}).items():
        with atomic_path(folder / name, size=len(data)) as temporary:
            temporary.write_bytes(data)
    if record.get("traceback"):
        write_text(folder / "error.txt", record["traceback"])
    saved = {"member": member.index, "label": member.label, "status": record["status"], "error": record["error"],
             "attempts": attempts, "wall_s": record.get("wall_s"), "cpu_s": record.get("cpu_s"),
             "stepping_cpu_s": record.get("stepping_cpu_s"),
             "worker": record.get("worker"), "scenario": scenario, "options": member.options,
             "metrics": record.get("metrics") or {}}
    for key in ("diverged", "warnings"):
        if record.get(key):
            saved[key] = record[key]
    # metrics.json is written last: its presence means the member finished (well or not).
    _write_json(folder / "metrics.json", saved)
    return saved


class _Progress:
    """A bar (members done, diverged, failed, rate) on a terminal; a few plain lines otherwise."""

    def __init__(self, total: int, label: str, mode):
        self.total, self.label, self.done, self.failed, self.diverged = total, label, 0, 0, 0
        self.started = time.perf_counter()
        tty = sys.stderr.isatty()
        self.mode = None if mode is False or total == 0 else ("bar" if (mode is None and tty) or mode == "bar"
                                                              else "lines")
        self.bar = None
        self.next_line = 0
        if self.mode == "bar":
            from tqdm import tqdm

            self.bar = tqdm(total=total, desc=label, unit="member", file=sys.stderr, dynamic_ncols=True)
            self.bar.set_postfix(diverged=0, failed=0)

    def update(self, status: str):
        self.done += 1
        self.failed += status == "failed"
        self.diverged += status == "diverged"
        if self.bar is not None:
            self.bar.update(1)
            self.bar.set_postfix(diverged=self.diverged, failed=self.failed)
        elif self.mode == "lines" and (self.done >= self.next_line or self.done == self.total):
            elapsed = time.perf_counter() - self.started
            rate = self.done / elapsed if elapsed > 0 else 0.0
            left = (self.total - self.done) / rate if rate > 0 else float("nan")
            print(f"{self.label}: {self.done}/{self.total} members, {self.diverged} diverged, {self.failed} failed, "
                  f"{rate:.2f} members/s, about {left:.0f} s left", file=sys.stderr, flush=True)
            self.next_line = self.done + max(1, self.total // 10)

    def close(self):
        if self.bar is not None:
            self.bar.close()


@contextlib.contextmanager
def cluster(workers: int | None = None, scheduler: str | None = None, connect_timeout: float = 10.0,
            timeout: float = 60.0):
    """A Dask client on a local cluster of ``workers`` processes (one thread each), or on the
    running ``scheduler``; closed when the block ends. Sweeps and tunes run their members here.

    Parameters
    ----------
    workers : int, optional
        Local worker processes (default: the CPUs). Ignored with ``scheduler``.
    scheduler : str, optional
        A running scheduler's address (checked by :func:`quadcosim.studies.sweep.folder.check_scheduler`).
    connect_timeout : float
        Seconds to reach the scheduler (s).
    timeout : float
        Seconds to wait for the first worker (s).

    Raises
    ------
    SweepError
        The scheduler cannot be reached, or no worker joined it in time.
    """
    from distributed import Client, LocalCluster

    with ExitStack() as stack:
        if scheduler:
            try:
                client = stack.enter_context(Client(scheduler, timeout=connect_timeout))
            except (OSError, TimeoutError) as error:
                raise SweepError(f"cannot reach the Dask scheduler at {scheduler} within {connect_timeout:g} s "
                                 f"({' '.join(str(error).split())[:200]}). Start one with `dask scheduler`, and "
                                 "workers with `dask worker ADDRESS`; --connect-timeout waits longer.") from None
            except (ValueError, TypeError, RuntimeError) as error:  # a transport refused its configuration
                raise SweepError(f"cannot use the Dask scheduler at {scheduler}: {type(error).__name__}: "
                                 f"{' '.join(str(error).split())[:200]}") from None
        else:
            import dask

            # Each worker death is reported at once, so that --retries counts every attempt.
            with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
                local = stack.enter_context(LocalCluster(
                    n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                    dashboard_address=None, silence_logs=logging.ERROR, worker_dashboard_address=None,
                    scheduler_kwargs={"dashboard_address": ":0"}))  # its HTTP server on a free port: no 8787 clash
            client = stack.enter_context(Client(local))
        try:
            client.wait_for_workers(1, timeout=timeout)
        except TimeoutError:
            raise SweepError(f"no Dask worker joined the scheduler {scheduler} within {timeout:g} s: start one "
                             f"with `dask worker {scheduler}`.") from None
        yield client


def run(plan: Plan, out, workers: int | None = None, scheduler: str | None = None, resume: bool = False,
        retries: int = 2, retry_errors: bool = False, keep_results: bool = False, progress=None,
        extra_metrics: str | None = None, timeout: float = 60.0, connect_timeout: float = 10.0) -> Summary:
    """Run every member of ``plan`` on Dask; results stream into ``out`` as members finish.

    The folder is held by this process while the sweep runs (a second sweep into it is
    refused); nothing is written in it before the cluster is up, so a sweep refused before then
    leaves nothing.

    Parameters
    ----------
    plan : Plan
        The scenario and its members (:func:`quadcosim.studies.sweep.plan`).
    out : path
        Sweep folder (see the module documentation).
    workers : int, optional
        Worker processes of the local cluster (default: the number of CPUs). Ignored with
        ``scheduler``.
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:8786``) to use instead.
    resume : bool
        Continue the sweep in ``out``: skip the members that finished well.
    retries : int
        How many more times a member is submitted after its worker died (and after it raised,
        with ``retry_errors``; members are deterministic, so an error usually repeats).
    retry_errors : bool
        Retry members that raised or gave a non-finite metric too.
    keep_results : bool
        Save each member's results and figures in its folder (off: a large sweep would fill
        the disk).
    progress : None, bool or "lines"
        None: a bar on a terminal, a few lines otherwise; False: silent.
    extra_metrics : str, optional
        ``"module:function"`` computing more metrics on the worker from ``(result, options)``
        (a dict of metric name to number or list of numbers, merged into the member's metrics:
        its columns in the table).
    timeout : float
        Seconds to wait for the first worker (s).
    connect_timeout : float
        Seconds to reach ``scheduler`` (s).

    Returns
    -------
    Summary

    Raises
    ------
    SweepError
        The folder does not match the plan, holds no sweep to resume, or the scheduler cannot be
        reached.
    quadcosim.studies.sweep.folder.FolderRefused
        The folder cannot be made or written, or the scheduler's address is not one.
    quadcosim.infra.files.FolderBusy
        Another process is writing the folder.
    quadcosim.studies.sweep.checks.MemberRefused
        A member's values would fail (:func:`quadcosim.studies.sweep.checks.check`); nothing was run.
    """
    if retries < 0:
        raise SweepError(f"retries = {retries} must be zero or more")
    from quadcosim.studies.sweep import checks, folder

    folder.check_scheduler(scheduler)
    out = folder.check_out(Path(out))
    if not resume and (out / "sweep.json").exists():  # said before the members are checked
        _prepare_folder(plan, out, resume).close()
    checks.check(plan)  # before the folder is written and the cluster started
    with folder.held(out):
        sweep = _Sweep(plan, out, resume)
        try:
            if sweep.left:
                with cluster(workers, scheduler, connect_timeout, timeout) as client:
                    _write_plan(plan, out)
                    client.register_plugin(Preload(plan.scenario))
                    sweep.stream(client, retries, retry_errors, keep_results, extra_metrics, progress)
                    sweep.streamed = time.perf_counter()
                sweep.shutdown = time.perf_counter() - sweep.streamed
            elif sweep.rows:
                sweep.flush(force=True)
        except BaseException:
            sweep.rows.close()
            raise
        return sweep.summary()


class _Sweep:
    """One call of :func:`run`: the table's rows, the members left to run, and the streaming of
    their results into the sweep folder."""

    def __init__(self, plan: Plan, out: Path, resume: bool):
        self.plan, self.out = plan, out
        self.rows = _prepare_folder(plan, out, resume)  # on disk, member by member: the client stays flat
        from quadcosim.studies.sweep import units

        names = list(plan.varied) + (list(plan.members[0].options) if len(plan.members) else [])
        self.rows.units = units.of_options(plan.scenario, names)  # the Parquet columns' metadata
        self.skipped = self.rows.ok + len(self.rows.divergences)
        self.left = len(plan.members) - self.skipped
        self.started = time.perf_counter()
        self.interrupted, self.ran, self.workers, self.startup = 0, 0, 0, 0.0
        self.streamed, self.shutdown = 0.0, 0.0
        self.last_write, self.write_cost = 0.0, 0.0

    def flush(self, force: bool = False):
        # Rewriting the table costs time proportional to its size: keep it under 5 % of the run.
        if force or time.perf_counter() - self.last_write >= 20 * self.write_cost:
            t = time.perf_counter()
            self.rows.write(self.out)
            self.last_write, self.write_cost = time.perf_counter(), time.perf_counter() - t

    def stream(self, client, retries, retry_errors, keep_results, extra_metrics, progress):
        """Submit every member left, and record each as it finishes (retrying as configured)."""
        from distributed import as_completed

        self.workers = len(client.scheduler_info(n_workers=-1)["workers"])
        self.startup = time.perf_counter() - self.started
        bar = _Progress(self.left, f"sweep {self.plan.name or self.plan.scenario}", progress)
        token, by_key = uuid.uuid4().hex[:8], {}

        def submit(member: Member, attempt: int):
            key = f"quadcosim-{token}-member-{member.index}-try-{attempt}"
            by_key[key] = (member, attempt)
            return client.submit(run_member, self.plan.scenario, member.options, keep_results, extra_metrics,
                                 key=key, pure=False)

        # Members go out in a bounded window, topped up as they finish: the client's futures and
        # the scheduler's tasks stay as many however large the plan.
        todo = (m for m in self.plan.members if not self.rows.finished(m.index))
        window = max(IN_FLIGHT_PER_WORKER * self.workers, IN_FLIGHT_LEAST)

        def top_up():
            while len(by_key) < window and (member := next(todo, None)) is not None:
                pending.add(submit(member, 1))

        pending = as_completed()
        try:
            top_up()
            for future in pending:
                member, attempt = by_key.pop(future.key)
                record, lost = _outcome(future)
                if record["status"] == "failed" and attempt <= retries and (lost or retry_errors):
                    pending.add(submit(member, attempt + 1))
                    continue
                top_up()
                saved = _save_member(self.out, member, record, attempt, self.plan.scenario)
                self.rows.add(member.index, table.row(saved, self.plan.varied))
                self.ran += 1
                bar.update(record["status"])
                self.flush()
        except KeyboardInterrupt as interrupt:  # Ctrl-C, or SIGTERM under the command line
            from quadcosim.infra.interrupts import signal_number

            self.interrupted = signal_number(interrupt)
            client.cancel(list(pending.futures))
        finally:
            bar.close()
            if self.rows:
                self.flush(force=True)

    def summary(self) -> Summary:
        rows = self.rows
        failures = sorted((i, label, error) for i, (label, error) in rows.failures.items())
        divergences = sorted((i, label, error) for i, (label, error) in rows.divergences.items())
        rows.close()
        return Summary(self.out, len(self.plan.members), rows.ok, len(failures), self.ran, self.skipped,
                       time.perf_counter() - self.started, self.workers, self.startup, self.shutdown, self.interrupted,
                       failures, len(divergences), divergences)


def _outcome(future) -> tuple[dict, bool]:
    """A finished member's record, and whether its worker was lost on the way."""
    try:
        record, lost = future.result(), False
    except Exception as error:  # the worker died (KilledWorker), or the connection
        record, lost = {"status": "failed", "error": f"worker lost: {type(error).__name__}: {error}",
                        "traceback": None, "metrics": {}, "wall_s": None, "worker": None}, True
    future.release()
    return record, lost
