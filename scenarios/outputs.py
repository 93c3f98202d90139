"""What a run leaves in its output folder, whatever ends it.

:class:`RunFiles` is the one place where a scenario's run writes its record and its
``metrics.json``. Every file goes through :func:`quadcosim.infra.files.atomic_path` (a temporary
name, ``fsync``, a rename), and the record and ``metrics.json`` are written with SIGINT and
SIGTERM held back (:func:`quadcosim.infra.interrupts.held`): a signal during the save lets it
finish, then stops the run. Whatever stops a run (a signal in any phase, a failure, a full
disk), ``metrics.json`` says what happened, in which phase, and which files were kept.
"""

from __future__ import annotations

import contextlib
import time
from pathlib import Path

import numpy as np
from quadcosim.orchestrator import Result, RunInterrupted, SimulationError

from quadcosim.infra.errors import UsageError
from quadcosim.infra.files import (
    LOCK_NAME,
    DiskFull,
    Reserve,
    free_bytes,
    megabytes,
    note_written,
    tracking,
    write_json,
)
from quadcosim.infra.interrupts import held, signal_name, signal_number, stopping

#: The file that keeps room for ``metrics.json`` on a disk that fills during the run (named as
#: a temporary file: ``--overwrite`` removes one a killed run left).
RESERVE = Reserve.NAME

#: Bytes kept for ``metrics.json`` (a run's is 3 to 10 kB).
RESERVE_BYTES = 64 * 1024
MEGABYTE = 1e6  # bytes, the unit of the record sizes in metrics.json


def empty_result(meta: dict | None = None) -> Result:
    """A record of no sample and no signal: what a run stopped before its loop leaves.

    Parameters
    ----------
    meta : dict, optional
        The run's meta data.
    """
    return Result(np.empty(0), [], np.empty((0, 0)), meta)


class RunFiles:
    """The files of one run in its output folder.

    Parameters
    ----------
    out : pathlib.Path
        The output folder, checked (:func:`quadcosim.infra.files.prepare_out_dir`).
    formats : sequence of str
        Record formats (``npz``, ``mat``, ``csv``).
    stated : quadcosim.scenarios.state.RunStated
        What ``metrics.json`` states in every case: scenario, options, faults, duration (s).
    units : dict
        Units of the options, merged into ``metrics.json``'s ``units``.
    compress : bool
        Compress the ``.npz`` and ``.mat`` files.
    """

    def __init__(self, out: Path, formats, stated, units: dict, compress: bool = False):
        self.out, self.formats, self.stated, self.units, self.compress = out, list(formats), stated, units, compress
        self.phase = "loading the scenario"
        self.names: list[str] = []  # files written, in order (tracked)
        self.not_written: dict[str, str] = {}  # file -> why it is missing
        self.result: Result | None = None  # the record, once the loop has ended
        self.record_saved = False
        self.save_cpu_seconds = 0.0
        self.saved = None  # the signals the files hold (None: all recorded)
        self.stream = None  # the record's stream writer, with --stream
        try:  # room kept for metrics.json, given back if the disk fills before it is written
            self.reserve = Reserve(out, RESERVE_BYTES)
        except DiskFull:
            raise NoRoom(f"no room in {out}/ for even its metrics.json ({megabytes(free_bytes(out))} free): free "
                         "space there or choose another --out folder") from None

    @contextlib.contextmanager
    def tracking(self):
        """Within the block, every file written into the folder is listed in :attr:`names`."""
        with tracking(self.out) as names:
            self.names = names
            yield self

    # ------------------------------------------------------------------ the record
    def keep_record(self, result: Result):
        """Write the record in every format (the signals of :attr:`saved`), signals held back until
        it is safe; with :attr:`stream`, close the record already streamed to disk instead.

        A format that does not fit (on the disk, or in memory) is left out, the reason noted
        in :attr:`not_written`; the others are written all the same.

        Parameters
        ----------
        result : quadcosim.orchestrator.Result
        """
        self._keep(result, self.saved, self.stream)

    def _keep(self, result: Result, signals, stream):
        self.result = result
        started = time.process_time()
        with held():
            if stream is not None and stream.path.is_dir():
                self._close_stream(stream, result)
            else:
                self._write_formats(result, signals)
            self.record_saved = True
        self.save_cpu_seconds += time.process_time() - started

    def record_megabytes(self) -> dict:
        """Size of each record file written, ``results_<format>_mb`` (MB, 1e6 bytes; the
        streamed folder's chunks as ``results_stream_mb``): what a run of this length and these
        signals takes on the disk."""
        sizes = {}
        for kind in self.formats:
            path = self.out / f"results.{kind}"
            if path.is_file():
                sizes[f"results_{kind}_mb"] = path.stat().st_size / MEGABYTE
        if self.stream is not None and self.stream.path.is_dir():
            sizes["results_stream_mb"] = sum(f.stat().st_size for f in self.stream.path.iterdir()) / MEGABYTE
        return sizes

    def _write_formats(self, result: Result, signals):
        for kind in self.formats:
            name = f"results.{kind}"
            try:
                result.save(self.out, formats=(kind,), signals=signals, compress=self.compress)
            except DiskFull as error:
                self.not_written[name] = str(error)
            except MemoryError as error:
                self.not_written[name] = (f"out of memory while writing it ({error or 'MemoryError'}); "
                                          "write fewer formats (--format npz) or record less")
            except OSError as error:  # the folder went away or became read-only under the run
                self.not_written[name] = f"{type(error).__name__}: {error}"

    def _close_stream(self, stream, result: Result):
        try:
            stream.close(result.meta, error=result.error)
        except DiskFull as error:
            self.not_written[stream.path.name + "/meta.json"] = str(error)
        note_written(stream.path)

    # ------------------------------------------------------------------ metrics.json
    def finish(self, metrics: dict):
        """Write ``metrics.json`` of a run that completed, listing its files."""
        self._write(metrics | self._files())

    def _files(self) -> dict:
        kept = {"files": sorted(n for n in self.names if n != "metrics.json")}
        if self.not_written:
            kept["files_not_written"] = dict(self.not_written)
        return kept

    def _write(self, metrics: dict):
        from quadcosim.scenarios.metrics import FAULT_UNITS, metric_units

        declared = metrics.get("units") or {}
        metrics = metrics | {"units": metric_units(metrics, declared) | self.units | {"injected_faults": FAULT_UNITS}}
        with held():
            try:
                write_json(self.out / "metrics.json", metrics)
            except DiskFull:
                if not self.reserve.held:
                    raise
                self.reserve.release()  # the room kept for this file
                write_json(self.out / "metrics.json", metrics)
            finally:
                self.reserve.release()

    def stopped(self, error: SimulationError, complete: bool = False):
        """Keep what a failed or interrupted run recorded (the signals of :attr:`saved`, or its
        :attr:`stream`), and a ``metrics.json`` saying where it stopped, in which phase and what
        was kept.

        Parameters
        ----------
        error : quadcosim.orchestrator.SimulationError
            What stopped the run; its ``result`` is what was recorded (None: nothing).
        complete : bool
            The loop had ended: the record is whole.
        """
        partial = error.result if error.result is not None else empty_result()
        signals = self.saved if partial.names else None  # stopped before the loop: an empty record, every format
        if not self.record_saved:
            partial.meta |= {"scenario": {"name": self.stated.scenario, "options": self.stated.options},
                             "faults": self.stated.injected_faults}
            self._keep(partial, signals, self.stream)
        interrupted = isinstance(error, RunInterrupted)
        record = self.result if self.result is not None else partial
        done = {"status": "interrupted" if interrupted else "failed", "error": str(error),
                "stopped_during": self.phase,
                "recorded_until_s": float(record.time[-1]) if len(record) else None,
                "samples": len(record), "record_complete": complete,
                "fmu_warnings": dict(record.meta.get("fmu_warnings", {}))}
        if interrupted:
            done["interrupted_by"] = signal_name(error.signal_number)
        if getattr(error, "traceback", None):  # a block of the user's raised: where, for its author
            done["traceback"] = error.traceback
        self._write(self.stated.metrics() | done | self._files())

    def interrupted(self, interrupt: BaseException) -> RunInterrupted:
        """Keep what was recorded when a signal stopped the run outside its loop (building,
        drawing, reporting), and say so in ``metrics.json``.

        Parameters
        ----------
        interrupt : KeyboardInterrupt
            The interrupt raised (:class:`quadcosim.infra.interrupts.Terminated` for SIGTERM).

        Returns
        -------
        quadcosim.orchestrator.RunInterrupted
            The error to raise.
        """
        number = stopping() or signal_number(interrupt)
        message = f"interrupted by {signal_name(number)} while {self.phase}"
        record = self.result if self.result is not None else empty_result()
        error = RunInterrupted(message, record, number)
        self.stopped(error, complete=self.result is not None)
        return error

    def failed(self, message: str) -> SimulationError:
        """A complete record whose report failed: ``metrics.json`` says so.

        Parameters
        ----------
        message : str
            What failed.

        Returns
        -------
        quadcosim.orchestrator.SimulationError
            The error to raise, with the record.
        """
        error = SimulationError(message, self.result)
        self.stopped(error, complete=True)
        return error

    def broke(self, error: OSError) -> SimulationError:
        """The disk filled, or the folder failed, in a phase outside the loop and the save
        (drawing the wiring diagram, say): keep what was recorded and a ``metrics.json`` saying
        so (written in the room kept for it).

        Parameters
        ----------
        error : OSError
            What failed (:class:`quadcosim.infra.files.DiskFull` for a full disk).

        Returns
        -------
        quadcosim.orchestrator.SimulationError
            The error to raise.
        """
        what = str(error) if isinstance(error, DiskFull) else f"{type(error).__name__}: {error}"
        failure = SimulationError(f"{what} (while {self.phase})", self.result)
        self.stopped(failure, complete=self.result is not None)
        return failure

    def refused(self, remove_folder: bool = False, fmu_refusal: Exception | None = None):
        """Remove what this run wrote: it was refused before it started (a value an FMU
        refused, a record too large), and the folder is left as it was; for an FMU of the
        user's refused (``fmu_refusal``), a ``metrics.json`` then says so.

        Parameters
        ----------
        remove_folder : bool
            The run made the folder: remove it too, if nothing else is in it (not with
            ``fmu_refusal``).
        fmu_refusal : quadcosim.orchestrator.fmu_checks.FMURefused, optional
            The refusal of an FMU before the loop: ``metrics.json`` gets ``status: refused``,
            its message (the block, the FMU, what is wrong and the fix), the options and an
            empty record (``samples: 0``, no result file).
        """
        import shutil

        for name in self.names:
            (self.out / name).unlink(missing_ok=True)
        if self.stream is not None and self.stream.path.is_dir():
            shutil.rmtree(self.stream.path)
        if fmu_refusal is not None:
            self.names.clear()
            self._write(self.stated.metrics() | {"status": "refused", "error": str(fmu_refusal),
                                                 "stopped_during": self.phase, "recorded_until_s": None,
                                                 "samples": 0, "record_complete": False, "files": []})
            return
        self.reserve.release()
        if remove_folder:
            remove_if_empty(self.out)

    # ------------------------------------------------------------------ room, before the run
    def check_room(self, rows: int, recorded: list[str], saved: list[str], decimation: int, stream: bool):
        """Refuse, before the run, a record that would not fit in memory with its writers, or
        whose files would not fit on the disk of the output folder.

        Parameters
        ----------
        rows : int
            Samples the run records.
        recorded, saved : list of str
            The signals recorded, and those the files hold.
        decimation : int
            The run's decimation, named as a way out.
        stream : bool
            The record goes to disk as the run goes (memory holds a window of it).

        Raises
        ------
        quadcosim.orchestrator.result.RecordTooLarge, NoRoom
            The figures, the limit that binds and the way out.
        """
        from collections import Counter

        from quadcosim.orchestrator.result import check_record_fits
        from quadcosim.orchestrator.signals import vector_groups

        from quadcosim.infra.memory import writers_peak

        groups = vector_groups(saved)
        if not stream:
            widest = max((len(m) for m in groups.values()), default=1)
            largest = max(Counter(n.partition(".")[0] for n in saved).values(), default=0)
            check_record_fits(rows, len(recorded), decimation,
                              writers_peak(rows, widest, self.formats, self.compress, largest))
        need = self.disk_need(rows, len(recorded) if stream else len(saved),
                              0 if stream else sum(len(m) for m in groups.values()))
        free = free_bytes(self.out)
        if free is not None and need > free:
            raise NoRoom(f"the record's files need about {megabytes(need, free)} in {self.out}/, where "
                         f"{megabytes(free, need)} are free. Free space there, choose another --out folder, or record "
                         f"less: every N-th step (--decimation N, now {decimation}), fewer signals (--record ...), "
                         "a shorter run")

    def disk_need(self, rows: int, signals: int, vector_members: int) -> int:
        """Bytes the uncompressed record files take (a compressed file is not counted: its size
        is not known before it is written).

        Parameters
        ----------
        rows : int
            Samples.
        signals : int
            Signals written (the time is counted besides).
        vector_members : int
            Signals that a ``.mat`` file also holds as members of a vector array.
        """
        from quadcosim.orchestrator.result import CSV_BYTES_PER_VALUE

        values = rows * (signals + 1)
        sizes = {"npz": 0 if self.compress else 8 * values, "csv": CSV_BYTES_PER_VALUE * values,
                 "mat": 0 if self.compress else 8 * (values + rows * vector_members)}
        return sum(sizes[kind] for kind in self.formats)


def remove_if_empty(folder: Path):
    """Remove ``folder`` when it holds nothing but this process's lock (a folder a refused
    run made is left as it was: absent)."""
    if folder.is_dir() and {p.name for p in folder.iterdir()} <= {LOCK_NAME}:
        (folder / LOCK_NAME).unlink(missing_ok=True)
        folder.rmdir()


class NoRoom(UsageError, ValueError):
    """The record's files would not fit on the disk of the output folder (refused input)."""
