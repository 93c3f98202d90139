"""Recorded signals of a run, indexed by name, with exports to .npz, .csv and MATLAB .mat.

The ``.npz`` and ``.mat`` files are compressed and carry the signals' units and the run's
options; vector signals (``IMU.acc``, ``Quadrotor.q``) are stored as N x k arrays and the
rotation matrix ``IMU.R_reel`` as N x 3 x 3. A record streamed to disk as the run went (by
:mod:`quadcosim.orchestrator.stream`) is read back by :class:`StreamedResult`; :meth:`Result.load` reads either.
"""

from __future__ import annotations

import csv
import json
import zipfile
from pathlib import Path

import numpy as np
from quadcosim.orchestrator.fmu import nearest
from quadcosim.orchestrator.signals import expand, matrix_shape, vector_groups
from quadcosim.orchestrator.values import float_text, integer_text, matlab_values

from quadcosim.infra.errors import UsageError
from quadcosim.infra.files import atomic_path, json_text
from quadcosim.infra.inputs import read_small_text, regular_file

#: Export formats of :meth:`Result.save`, as the command line's ``--format`` names them.
FORMATS = ("npz", "mat", "csv")

#: Bytes a value takes in a ``.csv`` file at most (``repr`` of a float64 and a comma).
CSV_BYTES_PER_VALUE = 25

#: What a run writes when no format is asked for: the NumPy archive alone.
DEFAULT_FORMATS = ("npz",)

#: Share of the available memory a record may take: the rest is for the scenario's report.
RECORD_SHARE = 0.8


def check_record_fits(rows: int, signals: int, decimation: int = 1, writers: int = 0) -> int:
    """Bytes a record will take; refuses one that would not fit in memory.

    Parameters
    ----------
    rows : int
        Samples to record.
    signals : int
        Recorded signals (float64 each).
    decimation : int
        The run's decimation, named in the message as a way out.
    writers : int
        Bytes the writers of the result files add at their peak
        (:func:`quadcosim.infra.memory.writers_peak`).

    Returns
    -------
    int
        Bytes of the record.

    Raises
    ------
    MemoryError
        The record and its writers exceed :data:`RECORD_SHARE` of the memory available
        (the machine's, ``ulimit -v`` or the control group's, whichever is smallest); the
        message gives the figures, the limit that binds and the way out.
    """
    from quadcosim.infra.memory import available, in_gigabytes

    record = rows * signals * 8
    need = record + writers
    room, source = available()
    if room is not None and need > RECORD_SHARE * room:
        count = rows if rows < 1e12 else f"{rows:.3g}"
        saving = f" and {in_gigabytes(writers)} more while its files are written" if writers else ""
        raise RecordTooLarge(
            f"this run would record {count} samples of {signals} signals, {in_gigabytes(record)}{saving}: more "
            f"than {RECORD_SHARE:.0%} of the {in_gigabytes(room)} of memory available (bound by {source})"
            ". Record less: every N-th "
            f"step (--decimation N, now {decimation}), fewer signals (--record SIGNAL ...), a shorter run, or "
            "--stream (the record goes to disk as the run goes).")
    return record


class RecordTooLarge(UsageError, MemoryError, ValueError):
    """A run's record would not fit in memory (a ``ValueError`` too: it is refused input)."""


def envelope(t: np.ndarray, y: np.ndarray, points: int = 2000) -> tuple[np.ndarray, np.ndarray]:
    """At most about ``2 points`` samples of the curve ``(t, y)`` that draw like all of it.

    The samples are cut into ``points`` runs; each run keeps its minimum and its maximum, in
    time order, so every peak survives. A figure a few thousand pixels wide then shows the
    same curve as from every sample, without a copy of the whole series in the figure.
    """
    n = len(y)
    if n <= 2 * points:
        return t, y
    size = -(-n // points)
    full = n // size * size
    keep = np.concatenate([run_extremes(y[:full], size), np.arange(full, n)])
    keep.sort()
    return t[keep], y[keep]


def run_extremes(y: np.ndarray, size: int) -> np.ndarray:
    """Indices of the minimum and of the maximum of each run of ``size`` samples of ``y``
    (whose length is a multiple of ``size``): the lower index of each pair, then the higher."""
    runs = y.reshape(-1, size)  # a view, even of a column of the record
    lows, highs = np.empty(len(runs), dtype=np.intp), np.empty(len(runs), dtype=np.intp)
    for first in range(0, len(runs), 64):  # a few runs at a time: a strided view is copied to reduce
        group = runs[first:first + 64]
        lows[first:first + 64], highs[first:first + 64] = group.argmin(axis=1), group.argmax(axis=1)
    starts = np.arange(0, len(y), size)
    lows += starts
    highs += starts
    return np.concatenate([np.minimum(lows, highs), np.maximum(lows, highs)])


class Result:
    """Signals recorded at ``time``. ``result["IMU.acc_x"]`` is one signal;
    ``result["IMU.acc"]`` stacks its components as columns.

    Parameters
    ----------
    time : ndarray
        Sample times (s).
    names : list of str
        Signal names, ``"Block.signal"``.
    data : ndarray, shape (len(time), len(names))
        The samples, in each signal's unit (SI).
    meta : dict, optional
        Run information (macro step, block order, connections, scenario).
    error : str, optional
        The message of the failure that ended the run early, if any; what was recorded up
        to it is kept.
    """

    def __init__(self, time: np.ndarray, names: list[str], data: np.ndarray, meta: dict | None = None,
                 error: str | None = None):
        self.time = time
        self.names = list(names)
        self.data = data
        self.meta = dict(meta or {})
        self.error = error
        self._index = {n: i for i, n in enumerate(self.names)}

    def __len__(self):
        return len(self.time)

    @property
    def units(self) -> dict[str, str]:
        """Unit of each signal (``"m/s2"``, ``"rad"``; ``""`` where none is known), with
        ``"time": "s"``."""
        return {"time": "s", **{n: "" for n in self.names}, **self.meta.get("units", {})}

    @property
    def options(self) -> dict:
        """The options of the scenario that made this result (empty for a bare run)."""
        return dict(self.meta.get("scenario", {}).get("options", {}))

    def __contains__(self, name):
        return name in self._index or bool(expand(name, self.names))

    def columns(self, name: str) -> list[str]:
        """The recorded names a signal or vector name stands for.

        Parameters
        ----------
        name : str
            ``"IMU.acc_x"`` or ``"IMU.acc"``.

        Returns
        -------
        list of str
            Recorded signal names.

        Raises
        ------
        KeyError
            Nothing recorded matches; the message names the nearest.
        """
        members = expand(name, self.names)
        if not members:
            if any(n == name or n.startswith(name + "_") for n in self.meta.get("left_out") or []):
                raise KeyError(f"no recorded signal {name!r}: the scenario left it out of its result files (it "
                               "follows from those kept); run it with --record all (record=['all'] from Python)")
            raise KeyError(f"no recorded signal {name!r}.{nearest(name, self.names)}")
        return members

    @property
    def dtypes(self) -> dict[str, str]:
        """The NumPy type of each signal that is not float64 (``{"Stair.counter": "int32"}``)."""
        return dict(self.meta.get("dtypes", {}))

    def typed(self, members: list[str], values: np.ndarray) -> np.ndarray:
        """``values`` of ``members`` in their own type when they share one that is not float64."""
        kinds = {self.meta.get("dtypes", {}).get(m) for m in members}
        if len(kinds) != 1 or None in kinds:
            return values
        return values.astype(kinds.pop())

    def __getitem__(self, name: str) -> np.ndarray:
        if name == "time":
            return self.time
        members = self.columns(name)
        columns = [self._index[m] for m in members]
        values = self.data[:, columns[0]] if len(columns) == 1 and members[0] == name else self.data[:, columns]
        return self.typed(members, values)

    # ------------------------------------------------------------------ windows
    def windows(self):
        """The record as consecutive windows of rows, each a :class:`Result`: the record
        itself when it is in memory (a streamed record gives one window per chunk, read one at
        a time), so that a report can take its statistics window by window.

        Yields
        ------
        Result
        """
        yield self

    def envelope(self, of, points: int = 2000) -> tuple[np.ndarray, np.ndarray]:
        """:func:`envelope` of the curve ``of(window)`` against time, over the whole record.

        Parameters
        ----------
        of : callable
            A window (:meth:`windows`) to the values drawn at its samples.
        points : int
            Runs of samples (each keeps its minimum and maximum).

        Returns
        -------
        (ndarray, ndarray)
            Times (s) and values kept.
        """
        return envelope(self.time, of(self), points)

    # ------------------------------------------------------------------ exports
    # Each export writes a temporary file beside the target and renames it when complete, so
    # an interrupt while saving never leaves a truncated file over earlier results.
    def _chosen(self, signals) -> list[str]:
        """The recorded names ``signals`` stand for (vector names allowed), in record order; all if None."""
        if signals is None:
            return self.names
        chosen = {member for name in signals for member in self.columns(name)}
        return [n for n in self.names if n in chosen]

    def _arrays(self, names):
        """``(name, array)`` to store, one at a time: each vector as one N x k array (a
        rotation matrix N x 3 x 3), every other signal as a vector of N values."""
        groups = vector_groups(names)
        grouped = {c for members in groups.values() for c in members}
        for name in names:
            if name not in grouped:
                yield name, self.typed([name], self.data[:, self._index[name]])
        for vector, members in groups.items():
            yield vector, self.typed(members, self._stacked(members).reshape(len(self.time), *matrix_shape(members)))

    def _stacked(self, members) -> np.ndarray:
        """The columns of ``members`` side by side: a view of the record when they are
        consecutive in it (a vector's components are), else a copy."""
        columns = [self._index[m] for m in members]
        if columns == list(range(columns[0], columns[0] + len(columns))):
            return self.data[:, columns[0]:columns[0] + len(columns)]
        return self.data[:, columns]

    def _description(self, names) -> dict:
        """The meta data written into the files: units, options, names and vectors included."""
        units = self.units
        return self.meta | {"error": self.error, "names": names, "units": {n: units[n] for n in ["time", *names]},
                            "options": self.options, "vectors": vector_groups(names)}

    def to_npz(self, path, signals=None, compress: bool = False) -> Path:
        """Write a NumPy archive (uncompressed unless ``compress``).

        It holds ``time`` (s), one array per scalar signal (in its own type: an FMU's Int32
        output is ``int32``, a Boolean ``bool``), one N x k array per vector signal
        (``"IMU.acc"``; ``"IMU.R_reel"`` is N x 3 x 3), and ``_meta``: JSON with ``units``
        (each signal's unit), ``options`` (the scenario's options), ``names`` and ``vectors``
        (the components of each vector). :meth:`from_npz` reads it back. The arrays are
        compressed one at a time: no copy of the whole record is made.

        Parameters
        ----------
        path : str or pathlib.Path
            The file, written atomically.
        signals : list of str, optional
            The signals to write (vector names allowed); all by default.
        compress : bool
            Deflate each array (level 1: as small as the default level 6 on these signals,
            twice as fast); about a third smaller and twenty times slower to write.

        Returns
        -------
        pathlib.Path
            ``path``.
        """
        from quadcosim.infra.progress import Every

        path = Path(path)
        every = Every(1.5)  # a status line now and then while a long record is written
        names = self._chosen(signals)
        method = zipfile.ZIP_DEFLATED if compress else zipfile.ZIP_STORED
        with atomic_path(path, size=8 * len(self) * (len(names) + 1)) as temporary, \
                zipfile.ZipFile(temporary, "w", method, allowZip64=True, compresslevel=1 if compress else None) \
                as archive:
            _write_array(archive, "time", self.time)
            for k, (name, values) in enumerate(self._arrays(names)):
                _write_array(archive, name, values)
                every.status(lambda k=k: f"writing {path.name}: {k + 1} arrays written")
            _write_array(archive, "_meta", np.array(json_text(self._description(names), indent=None)))
        return path

    def to_csv(self, path, signals=None) -> Path:
        """Write one row per sample: ``time`` (s) then every signal at full precision, integers as integers.

        Parameters
        ----------
        path : str or pathlib.Path
            The file, written atomically.
        signals : list of str, optional
            The signals to write (vector names allowed); all by default.

        Returns
        -------
        pathlib.Path
            ``path``.
        """
        path = Path(path)
        names = self._chosen(signals)
        with atomic_path(path, size=CSV_BYTES_PER_VALUE * len(self) * (len(names) + 1)) as temporary, \
                temporary.open("w", newline="") as handle:
            writer = csv.writer(handle)
            columns = [self._index[n] for n in names]
            dtypes = self.meta.get("dtypes", {})
            text = [integer_text if np.dtype(dtypes.get(n, "float64")).kind in "biu" else float_text for n in names]
            writer.writerow(["time", *names])
            for t, row in zip(self.time, self.data, strict=True):
                writer.writerow([repr(float(t)), *(f(row[c]) for f, c in zip(text, columns, strict=True))])
        return path

    def to_mat(self, path, signals=None, compress: bool = False) -> Path:
        """Write a MATLAB file (uncompressed unless ``compress``).

        One struct per block, each signal an N x 1 column in its own type (``IMU.acc_x`` reads
        ``IMU.acc_x`` in MATLAB; an FMU's Int32 output is an ``int32``, a Boolean a ``logical``)
        and each vector also an N x k array (``IMU.acc``; ``IMU.R_reel`` N x 3 x 3); ``time`` (s);
        ``units``, a struct per block giving each field's unit
        (``units.IMU.acc_x`` is ``'m/s2'``); ``options``, the scenario's options; ``meta``,
        the run's step, decimation, scenario and error message.

        Parameters
        ----------
        path : str or pathlib.Path
            The file, written atomically.
        signals : list of str, optional
            The signals to write (vector names allowed); all by default.
        compress : bool
            Compress each variable (a block's struct is then held in memory whole while it is
            compressed).

        Returns
        -------
        pathlib.Path
            ``path``.
        """
        from scipy.io import savemat

        blocks: dict[str, dict[str, np.ndarray]] = {}
        units: dict[str, dict[str, str]] = {}
        every_unit = self.units
        names = self._chosen(signals)
        groups = vector_groups(names)
        for name in names:
            block, _, signal = name.partition(".")
            blocks.setdefault(block, {})[signal] = self.typed([name], self.data[:, self._index[name]])
            units.setdefault(block, {})[signal] = every_unit[name]
        for vector, members in groups.items():
            block, _, signal = vector.partition(".")
            blocks[block][signal] = self.typed(members, self._stacked(members).reshape(len(self.time),
                                                                                       *matrix_shape(members)))
            units[block][signal] = every_unit[members[0]]
        scenario = self.meta.get("scenario", {})
        meta = {"scenario": scenario.get("name", ""), "dt_s": self.meta.get("dt", np.nan),
                "decimation": self.meta.get("decimation", 1), "error": self.error or "",
                "faults": [json_text(f, indent=None) for f in self.meta.get("faults", [])]}
        size = 8 * len(self) * (1 + len(names) + sum(len(m) for m in groups.values()))
        with atomic_path(path, size=size) as temporary:
            savemat(temporary, {"time": self.time, **blocks, "units": units | {"time": "s"},
                                "options": matlab_values(self.options), "meta": matlab_values(meta)},
                    long_field_names=True, do_compression=compress, oned_as="column")
        return Path(path)

    @classmethod
    def load(cls, path) -> Result:
        """Read a record in either format: a ``.npz`` file, a ``results.stream`` folder, or a
        run's output folder holding one of them.

        Parameters
        ----------
        path : str or pathlib.Path
            The file or folder.

        Returns
        -------
        Result
            The record (read lazily, one signal at a time, from a stream folder).
        """
        path = Path(path)
        if path.is_dir() and (path / FOLDER).is_dir():
            path = path / FOLDER
        elif path.is_dir() and (path / "results.npz").is_file():
            path = path / "results.npz"
        if path.is_dir():
            if not (path / "meta.json").is_file():
                raise FileNotFoundError(f"{path}: neither a results.npz nor a record streamed by --stream")
            return StreamedResult(path)
        return cls.from_npz(path)

    @classmethod
    def from_npz(cls, path) -> Result:
        """Read a result written by :meth:`to_npz` (or by earlier versions, one array per signal).

        Parameters
        ----------
        path : str or pathlib.Path
            The archive.

        Returns
        -------
        Result
            With its meta data (units and options included) and error message.
        """
        regular_file(path, "a result", "give a run's results.npz (or its folder)")
        # the file opened here and closed here: NumPy leaves its own handle open on a damaged archive
        with open(path, "rb") as file, np.load(file) as archive:
            meta = json.loads(str(archive["_meta"]))
            time = archive["time"]
            vectors = meta.pop("vectors", {})
            names = meta.pop("names", None) or [n for n in archive.files if n not in ("time", "_meta")]
            data = np.empty((len(time), len(names)))
            column = {n: i for i, n in enumerate(names)}
            for stored in archive.files:
                if stored in vectors:
                    values = archive[stored].reshape(len(time), -1)
                    for k, member in enumerate(vectors[stored]):
                        data[:, column[member]] = values[:, k]
                elif stored in column:
                    data[:, column[stored]] = archive[stored]
            meta.pop("options", None)
            return cls(time, names, data, meta, meta.pop("error", None))

    def save(self, out_dir, csv: bool = False, formats=DEFAULT_FORMATS, signals=None,
             compress: bool = False) -> list[Path]:
        """Write ``results.<format>`` into ``out_dir`` for each of ``formats``.

        Parameters
        ----------
        out_dir : str or pathlib.Path
            The folder (created if missing).
        csv : bool
            Add ``"csv"`` to ``formats``.
        formats : sequence of str
            A subset of :data:`FORMATS`; default :data:`DEFAULT_FORMATS` (the ``.npz`` alone).
        signals : list of str, optional
            The signals to write (vector names allowed); all by default.
        compress : bool
            Compress the ``.npz`` and ``.mat`` files.

        Returns
        -------
        list of pathlib.Path
            The files written.
        """
        formats = list(dict.fromkeys([*formats, *(["csv"] if csv else [])]))
        unknown = [f for f in formats if f not in FORMATS]
        if unknown:
            raise ValueError(f"unknown result format {', '.join(unknown)}; formats: {', '.join(FORMATS)}")
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        written = []
        for kind in formats:
            path = out / f"results.{kind}"
            if kind == "csv":
                written.append(self.to_csv(path, signals))
            else:
                written.append((self.to_npz if kind == "npz" else self.to_mat)(path, signals, compress))
        return written

    # ------------------------------------------------------------------ plots
    def plot(self, *names, ax=None, scale: float = 1.0, label_prefix: str = "", unit: str | None = None):
        """Plot signals against time; long series are drawn from their :func:`envelope`, integer
        and Boolean signals as steps (held from one sample to the next).

        The y axis is labelled with the names and their unit, from the variable tables (the
        run's ``meta["units"]``), or ``unit`` when given (as it must be with a ``scale``:
        ``scale=180 / pi, unit="deg"``).

        Parameters
        ----------
        *names : str
            Signal or vector names.
        ax : matplotlib.axes.Axes, optional
            Where to draw; a new figure if None.
        scale : float
            Factor applied to the values (e.g. ``180 / pi`` for degrees).
        label_prefix : str
            Prefix of each curve's label.
        unit : str, optional
            Unit of the values drawn (after ``scale``); by default the signals' own unit
            (``1`` for a dimensionless one, as the variable tables write it).

        Returns
        -------
        matplotlib.axes.Axes
            The axes.

        Raises
        ------
        ValueError
            A ``scale`` without a ``unit``.
        """
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(8, 3), layout="constrained")  # savefig keeps the axis labels
        if unit is None and scale != 1.0:
            raise ValueError(f"plot of {', '.join(names)} scaled by {scale:g}: give the unit of the scaled values "
                             "(unit=...)")
        known = self.meta.get("units", {})
        parts = []  # "name (unit)", one per name, or one for all when they share their unit
        for name in names:
            members = self.columns(name)
            for member in members:
                t, y = envelope(self.time, self[member])
                steps = np.dtype(self.meta.get("dtypes", {}).get(member, "float64")).kind in "biu"
                ax.plot(t, y * scale, label=label_prefix + member, drawstyle="steps-post" if steps else "default")
            found = {known[m] for m in members if known.get(m)}  # "" is a unit not known
            shown = unit if unit is not None else found.pop() if len(found) == 1 else "unit unknown"
            parts.append((name, shown))
        if len({shown for _, shown in parts}) == 1:
            ax.set_ylabel(f"{', '.join(name for name, _ in parts)} ({parts[0][1]})")
        else:
            ax.set_ylabel(", ".join(f"{name} ({shown})" for name, shown in parts))
        ax.set_xlabel("time (s)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="best")
        return ax


#: Rows gathered at a time when a column of the record is written (a few MB at most).
WRITE_ROWS = 2 ** 16


#: The folder name of a streamed record inside a run's output folder.
FOLDER = "results.stream"


class DamagedRecord(UsageError, ValueError):
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
            meta = json.loads(read_small_text(folder / "meta.json", "a streamed record's meta.json",
                                              "run the scenario again with --stream", error=DamagedRecord))
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
            return self.typed(members, self._column(self._index[name]))
        return self.typed(members, np.stack([self._column(self._index[m]) for m in members], axis=1))

    def windows(self):
        """One :class:`Result` per chunk, read one at a time (see :meth:`Result.windows`)."""
        for path in self.chunk_files:
            block = np.load(path)
            yield Result(block[0], self.names, block[1:].T, self.meta, self.error)

    def envelope(self, of, points: int = 2000) -> tuple[np.ndarray, np.ndarray]:
        """:func:`quadcosim.orchestrator.result.envelope` of ``of(window)``, chunk by chunk: the runs
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


def _write_array(archive: zipfile.ZipFile, name: str, values: np.ndarray):
    """One ``name.npy`` member of a NumPy archive, the bytes ``numpy.save`` writes.

    A column of the record is strided: it is gathered :data:`WRITE_ROWS` rows at a time into
    one contiguous block handed to the archive as it is (``numpy.lib.format.write_array``
    copies each block twice).
    """
    values = np.asanyarray(values)
    if values.dtype.hasobject or values.dtype.kind not in "fiub":  # the JSON meta: numpy's own writer
        with archive.open(f"{name}.npy", "w", force_zip64=True) as member:
            np.lib.format.write_array(member, values, allow_pickle=False)
        return
    header = np.lib.format.header_data_from_array_1_0(values)
    header["fortran_order"] = False  # the bytes below are in C order, whatever the layout of values
    with archive.open(f"{name}.npy", "w", force_zip64=True) as member:
        try:
            np.lib.format.write_array_header_1_0(member, header)
        except ValueError:  # a header too long for format 1.0, as numpy.save falls back
            np.lib.format.write_array_header_2_0(member, header)
        if values.flags.c_contiguous:
            member.write(values.data if values.ndim else values.tobytes())
            return
        for first in range(0, len(values), WRITE_ROWS):
            member.write(np.ascontiguousarray(values[first:first + WRITE_ROWS]).data)
