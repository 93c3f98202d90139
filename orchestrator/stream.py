"""A record written to disk in chunks as the run goes, and read back by name.

With ``--stream`` the master records into a window of rows (:data:`WINDOW_BYTES`, touched
once before the loop) and, each time it is full, writes it out as the next chunk of the
folder ``results.stream/``; memory then stays flat however long the run. The folder holds:

- ``chunk-000000.npy``, ``chunk-000001.npy``, ...: each a float64 array of ``1 + S`` rows
  (the time in s, then the ``S`` signals in the order of ``meta.json``'s ``names``) by the
  samples of the chunk, so that one signal of one chunk is contiguous on disk;
- ``meta.json``: ``names``, ``units``, the run's meta data (step, decimation, scenario,
  error), ``samples`` and ``chunks`` once the run has ended (written at the start too, so that
  a run killed outright leaves a readable folder: its complete chunks).

Every chunk and ``meta.json`` go through :func:`orchestrator.files.atomic_path`: a chunk on
disk is whole. :class:`StreamedResult` reads the folder back: a signal is gathered from the
chunks when asked for, so that a report reads one signal at a time.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from orchestrator.files import atomic_path, write_json
from orchestrator.result import Result, envelope, run_extremes

#: Bytes of the window of rows held in memory before they go to disk.
WINDOW_BYTES = 8 * 2 ** 20

#: The folder name of a streamed record inside a run's output folder.
FOLDER = "results.stream"


def window_rows(signals: int, total_rows: int) -> int:
    """Rows of the window for ``signals`` signals: :data:`WINDOW_BYTES` of them, at most the
    record's ``total_rows``."""
    return max(1, min(total_rows, WINDOW_BYTES // (8 * max(signals, 1))))


class StreamWriter:
    """Writes a record's rows into ``folder`` as chunk files.

    Parameters
    ----------
    folder : str or pathlib.Path
        The stream's folder (created; it must not hold a stream already).
    """

    def __init__(self, folder):
        self.path = Path(folder)
        self.chunks = 0
        self.samples = 0
        self.names: list[str] = []
        self.units: dict[str, str] = {}

    def start(self, names, units: dict):
        """Create the folder and its first ``meta.json``, before the first row.

        Parameters
        ----------
        names : sequence of str
            The recorded signals, in the order of the rows' columns.
        units : dict
            Unit of each signal.
        """
        self.names, self.units = list(names), dict(units)
        self.path.mkdir(parents=True, exist_ok=False)
        self._write_meta({}, None, ended=False)

    def write(self, time: np.ndarray, rows: np.ndarray):
        """Append ``rows`` (samples x signals) taken at ``time`` (s) as the next chunk."""
        if not len(rows):
            return
        block = np.empty((1 + rows.shape[1], len(rows)))
        block[0] = time
        block[1:] = rows.T
        with atomic_path(self.path / f"chunk-{self.chunks:06d}.npy", size=block.nbytes + 128) as temporary:
            np.save(temporary, block)
        self.chunks += 1
        self.samples += len(rows)

    def close(self, meta: dict, error: str | None = None):
        """Write the final ``meta.json``: the run's meta data and the samples written.

        Parameters
        ----------
        meta : dict
            The run's meta data (step, decimation, scenario, warnings).
        error : str, optional
            The message of the failure that ended the run.
        """
        self._write_meta(meta, error, ended=True)

    def _write_meta(self, meta: dict, error: str | None, ended: bool):
        description = meta | {"names": self.names, "units": {"time": "s", **self.units}, "error": error,
                              "samples": self.samples, "chunks": self.chunks, "ended": ended}
        write_json(self.path / "meta.json", description)


class DamagedRecord(ValueError):
    """A streamed record whose chunks are missing or whose description is unreadable."""


def _check_chunks(folder: Path, chunk_files: list[Path], meta: dict):
    """Refuse a stream whose chunks are not ``chunk-000000.npy`` onwards without a gap, or fewer
    than its finished ``meta.json`` lists (chunks removed, or a copy cut short)."""
    expected = [f"chunk-{k:06d}.npy" for k in range(len(chunk_files))]
    gaps = [e for e, found in zip(expected, chunk_files, strict=True) if found.name != e]
    listed = meta.get("chunks") if meta.get("ended") else None
    if gaps or (listed is not None and len(chunk_files) < listed):
        missing = gaps[0] if gaps else f"chunk-{len(chunk_files):06d}.npy"
        count = f"{listed} chunks ({meta.get('samples')} samples)" if listed is not None else "its chunks"
        raise DamagedRecord(f"{folder}: the streamed record is damaged: its meta.json lists {count}, "
                            f"{len(chunk_files)} are there ({missing} is missing); it cannot be read whole")


class StreamedResult(Result):
    """A record read from a stream folder; a signal is read from disk when asked for.

    Parameters
    ----------
    folder : str or pathlib.Path
        A folder written by :class:`StreamWriter` (complete, or cut short: its whole chunks
        are read).
    """

    def __init__(self, folder):
        folder = Path(folder)
        try:
            meta = json.loads((folder / "meta.json").read_text())
            names = meta.pop("names")
        except (OSError, ValueError, KeyError, TypeError, AttributeError) as error:
            raise DamagedRecord(f"{folder}: its meta.json is damaged ({type(error).__name__}: {error})") from None
        self.folder = folder
        self.chunk_files = sorted(folder.glob("chunk-*.npy"))
        if meta.get("ended"):
            self.chunk_files = self.chunk_files[:meta["chunks"]]
        _check_chunks(folder, self.chunk_files, meta)
        error = meta.pop("error", None)
        lengths = [self._chunk(path).shape[1] for path in self.chunk_files]  # from the headers alone
        time = np.empty(sum(lengths))
        at = 0
        for path, length in zip(self.chunk_files, lengths, strict=True):  # one chunk mapped at a time
            time[at:at + length] = self._chunk(path)[0]
            at += length
        super().__init__(time, names, None, meta, error)

    @staticmethod
    def _chunk(path: Path) -> np.ndarray:
        return np.load(path, mmap_mode="r")

    def _column(self, index: int) -> np.ndarray:
        """One signal, gathered from every chunk (row ``1 + index`` of each)."""
        column = np.empty(len(self.time))
        at = 0
        for path in self.chunk_files:
            values = self._chunk(path)[1 + index]
            column[at:at + len(values)] = values
            at += len(values)
        return column

    @property
    def data(self) -> np.ndarray:
        """Every signal as one samples x signals array (read whole: for small records)."""
        whole = np.empty((len(self.time), len(self.names)))
        for k in range(len(self.names)):
            whole[:, k] = self._column(k)
        return whole

    @data.setter
    def data(self, value):
        if value is not None:
            raise AttributeError("a streamed record is read from its folder; it cannot be replaced")

    def __getitem__(self, name: str) -> np.ndarray:
        if name == "time":
            return self.time
        members = self.columns(name)
        if len(members) == 1 and members[0] == name:
            return self._column(self._index[name])
        return np.stack([self._column(self._index[m]) for m in members], axis=1)

    def windows(self):
        """One :class:`Result` per chunk, read one at a time (see :meth:`Result.windows`)."""
        for path in self.chunk_files:
            block = np.load(path)
            yield Result(block[0], self.names, block[1:].T, self.meta, self.error)

    def envelope(self, of, points: int = 2000) -> tuple[np.ndarray, np.ndarray]:
        """:func:`orchestrator.result.envelope` of ``of(window)``, chunk by chunk: the runs
        are those of the whole record, and a run that spans two chunks is carried over, so the
        samples kept are those of the envelope of the whole curve.

        Parameters
        ----------
        of : callable
            A window (one chunk, a :class:`Result`) to the values drawn at its samples.
        points : int
            Runs of samples (each keeps its minimum and maximum).
        """
        n = len(self.time)
        if n <= 2 * points:
            return envelope(self.time, of(self), points)
        size = -(-n // points)
        times, values = [], []
        carry_t, carry_y = np.empty(0), np.empty(0)
        for window in self.windows():
            t, y = np.concatenate([carry_t, window.time]), np.concatenate([carry_y, of(window)])
            full = len(y) // size * size
            keep = run_extremes(y[:full], size)
            keep.sort()
            times.append(t[keep])
            values.append(y[keep])
            carry_t, carry_y = t[full:], y[full:]
        return np.concatenate([*times, carry_t]), np.concatenate([*values, carry_y])
