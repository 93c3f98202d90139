"""Recorded signals of a run, indexed by name, with exports to .npz, .csv and MATLAB .mat."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from orchestrator.files import atomic_path
from orchestrator.fmu import nearest

#: Export formats of :meth:`Result.save`, as the command line's ``--format`` names them.
FORMATS = ("npz", "mat", "csv")


def available_memory() -> int | None:
    """Memory the kernel can give without swapping (bytes): ``MemAvailable`` of
    ``/proc/meminfo``, or None where that is not known."""
    try:
        with open("/proc/meminfo") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return None


#: Share of the available memory a record may take: the rest is for the scenario's report.
RECORD_SHARE = 0.8


def check_record_fits(rows: int, signals: int, decimation: int = 1) -> int:
    """Bytes a record will take; refuses one that would not fit in memory.

    Parameters
    ----------
    rows : int
        Samples to record.
    signals : int
        Recorded signals (float64 each).
    decimation : int
        The run's decimation, named in the message as a way out.

    Returns
    -------
    int
        Bytes of the record.

    Raises
    ------
    MemoryError
        The record exceeds :data:`RECORD_SHARE` of the available memory; the message gives
        the figure and the way out.
    """
    need = rows * signals * 8
    available = available_memory()
    if available is not None and need > RECORD_SHARE * available:
        count = rows if rows < 1e12 else f"{rows:.3g}"
        raise RecordTooLarge(
            f"this run would record {count} samples of {signals} signals, {need / 1e9:.3g} GB, more than "
            f"{RECORD_SHARE:.0%} of the {available / 1e9:.3g} GB of memory available. Record less: every N-th "
            f"step (--decimation N, now {decimation}), fewer signals (--record SIGNAL ...), or a shorter run.")
    return need


class RecordTooLarge(MemoryError, ValueError):
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
    runs = y[:full].reshape(-1, size)  # a view, even of a column of the record
    lows, highs = np.empty(len(runs), dtype=np.intp), np.empty(len(runs), dtype=np.intp)
    for first in range(0, len(runs), 64):  # a few runs at a time: a strided view is copied to reduce
        group = runs[first:first + 64]
        lows[first:first + 64], highs[first:first + 64] = group.argmin(axis=1), group.argmax(axis=1)
    starts = np.arange(0, full, size)
    lows += starts
    highs += starts
    keep = np.concatenate([np.minimum(lows, highs), np.maximum(lows, highs), np.arange(full, n)])
    keep.sort()
    return t[keep], y[keep]


def expand(name: str, available) -> list[str]:
    """Names a signal name stands for: itself, or its components.

    ``"IMU.acc"`` stands for ``IMU.acc_x``, ``IMU.acc_y``, ``IMU.acc_z``;
    ``"MotorMagnetics.omega_r"`` for ``omega_r1`` to ``omega_r4``; ``"Quadrotor.q"`` for
    ``q0`` to ``q3``; ``"IMU.R_reel"`` for ``R_reel_11`` to ``R_reel_33``.

    Parameters
    ----------
    name : str
        A signal or vector name.
    available : sequence of str
        The names to choose from.

    Returns
    -------
    list of str
        The matching names, in the order of ``available``; empty if none.
    """
    available = list(available)
    if name in available:
        return [name]
    members = [s for s in available if s.startswith(name) and _is_component(s[len(name):])]
    return members


def _is_component(suffix: str) -> bool:
    if suffix.startswith("_"):
        suffix = suffix[1:]
    return bool(suffix) and (suffix in ("x", "y", "z") or suffix.isdigit())


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
            raise KeyError(f"no recorded signal {name!r}.{nearest(name, self.names)}")
        return members

    def __getitem__(self, name: str) -> np.ndarray:
        if name == "time":
            return self.time
        members = self.columns(name)
        columns = [self._index[m] for m in members]
        return self.data[:, columns[0]] if len(columns) == 1 and members[0] == name else self.data[:, columns]

    # ------------------------------------------------------------------ exports
    # Each export writes a temporary file beside the target and renames it when complete, so
    # an interrupt while saving never leaves a truncated file over earlier results.
    def to_npz(self, path) -> Path:
        """Write a NumPy archive: ``time``, one array per signal, and ``_meta`` (JSON).

        Parameters
        ----------
        path : str or pathlib.Path
            The file, written atomically.

        Returns
        -------
        pathlib.Path
            ``path``.
        """
        path = Path(path)
        with atomic_path(path) as temporary:
            np.savez(temporary, time=self.time, **{n: self.data[:, i] for i, n in enumerate(self.names)},
                     _meta=json.dumps(self.meta | {"error": self.error}, default=float))
        return path

    def to_csv(self, path) -> Path:
        """Write one row per sample: ``time`` (s) then every signal, full precision.

        Parameters
        ----------
        path : str or pathlib.Path
            The file, written atomically.

        Returns
        -------
        pathlib.Path
            ``path``.
        """
        path = Path(path)
        with atomic_path(path) as temporary, temporary.open("w", newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(["time", *self.names])
            for t, row in zip(self.time, self.data, strict=True):
                writer.writerow([repr(float(t)), *(repr(float(v)) for v in row)])
        return path

    def to_mat(self, path) -> Path:
        """Write a MATLAB file: one struct per block (``IMU.acc_x`` reads ``IMU.acc_x`` in MATLAB).

        Parameters
        ----------
        path : str or pathlib.Path
            The file, written atomically.

        Returns
        -------
        pathlib.Path
            ``path``.
        """
        from scipy.io import savemat

        blocks: dict[str, dict[str, np.ndarray]] = {}
        for i, name in enumerate(self.names):
            block, _, signal = name.partition(".")
            blocks.setdefault(block, {})[signal] = self.data[:, i]
        with atomic_path(path) as temporary:
            savemat(temporary, {"time": self.time, **blocks}, long_field_names=True)
        return Path(path)

    @classmethod
    def from_npz(cls, path) -> Result:
        """Read a result written by :meth:`to_npz`.

        Parameters
        ----------
        path : str or pathlib.Path
            The archive.

        Returns
        -------
        Result
            With its meta data and error message.
        """
        with np.load(path) as archive:
            names = [n for n in archive.files if n not in ("time", "_meta")]
            meta = json.loads(str(archive["_meta"]))
            data = np.column_stack([archive[n] for n in names]) if names else np.empty((len(archive["time"]), 0))
            return cls(archive["time"], names, data, meta, meta.pop("error", None))

    def save(self, out_dir, csv: bool = False, formats=("npz", "mat")) -> list[Path]:
        """Write ``results.<format>`` into ``out_dir`` for each of ``formats`` (a subset of
        :data:`FORMATS`; ``csv=True`` adds ``"csv"``). Returns the paths written."""
        formats = list(dict.fromkeys([*formats, *(["csv"] if csv else [])]))
        unknown = [f for f in formats if f not in FORMATS]
        if unknown:
            raise ValueError(f"unknown result format {', '.join(unknown)}; formats: {', '.join(FORMATS)}")
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        writers = {"npz": self.to_npz, "mat": self.to_mat, "csv": self.to_csv}
        return [writers[f](out / f"results.{f}") for f in formats]

    # ------------------------------------------------------------------ plots
    def plot(self, *names, ax=None, scale: float = 1.0, label_prefix: str = "", unit: str | None = None):
        """Plot signals against time; long series are drawn from their :func:`envelope`.

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
            _, ax = plt.subplots(figsize=(8, 3))
        if unit is None and scale != 1.0:
            raise ValueError(f"plot of {', '.join(names)} scaled by {scale:g}: give the unit of the scaled values "
                             "(unit=...)")
        known = self.meta.get("units", {})
        parts = []  # "name (unit)", one per name, or one for all when they share their unit
        for name in names:
            members = self.columns(name)
            for member in members:
                t, y = envelope(self.time, self[member])
                ax.plot(t, y * scale, label=label_prefix + member)
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
