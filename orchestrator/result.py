"""Recorded signals of a run, indexed by name, with exports to .npz, .csv and MATLAB .mat."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from orchestrator.fmu import nearest


def expand(name: str, available) -> list[str]:
    """Names a signal name stands for: itself, or its components.

    ``"IMU.acc"`` stands for ``IMU.acc_x``, ``IMU.acc_y``, ``IMU.acc_z``;
    ``"MotorMagnetics.omega_r"`` for ``omega_r1`` to ``omega_r4``; ``"Quadrotor.q"`` for
    ``q0`` to ``q3``; ``"IMU.R_reel"`` for ``R_reel_11`` to ``R_reel_33``.
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
    """Signals recorded at ``time`` (s). ``result["IMU.acc_x"]`` is one signal;
    ``result["IMU.acc"]`` stacks its components as columns.

    ``error`` holds the message of the failure that ended the run early, if any; what was
    recorded up to it is kept.
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
    def to_npz(self, path) -> Path:
        path = Path(path)
        np.savez(path, time=self.time, **{n: self.data[:, i] for i, n in enumerate(self.names)},
                 _meta=json.dumps(self.meta | {"error": self.error}))
        return path

    def to_csv(self, path) -> Path:
        path = Path(path)
        with path.open("w", newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(["time", *self.names])
            for t, row in zip(self.time, self.data, strict=True):
                writer.writerow([repr(float(t)), *(repr(float(v)) for v in row)])
        return path

    def to_mat(self, path) -> Path:
        """MATLAB file: one struct per block (``IMU.acc_x`` becomes ``IMU.acc_x`` in MATLAB)."""
        from scipy.io import savemat

        blocks: dict[str, dict[str, np.ndarray]] = {}
        for i, name in enumerate(self.names):
            block, _, signal = name.partition(".")
            blocks.setdefault(block, {})[signal] = self.data[:, i]
        savemat(Path(path), {"time": self.time, **blocks}, long_field_names=True)
        return Path(path)

    @classmethod
    def from_npz(cls, path) -> Result:
        with np.load(path) as archive:
            names = [n for n in archive.files if n not in ("time", "_meta")]
            meta = json.loads(str(archive["_meta"]))
            data = np.column_stack([archive[n] for n in names]) if names else np.empty((len(archive["time"]), 0))
            return cls(archive["time"], names, data, meta, meta.pop("error", None))

    def save(self, out_dir, csv: bool = False) -> list[Path]:
        """Write ``results.npz`` and ``results.mat`` (and ``results.csv``) into ``out_dir``."""
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        written = [self.to_npz(out / "results.npz"), self.to_mat(out / "results.mat")]
        if csv:
            written.append(self.to_csv(out / "results.csv"))
        return written

    # ------------------------------------------------------------------ plots
    def plot(self, *names, ax=None, scale: float = 1.0, label_prefix: str = ""):
        """Plot signals against time on ``ax`` (a new figure if None); returns the axes."""
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(8, 3))
        for name in names:
            for member in self.columns(name):
                ax.plot(self.time, self[member] * scale, label=label_prefix + member)
        ax.set_xlabel("time (s)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="best")
        return ax
