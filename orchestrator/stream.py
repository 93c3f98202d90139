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

Every chunk and ``meta.json`` go through :func:`quadcosim.infra.files.atomic_path`: a chunk on
disk is whole. :class:`quadcosim.orchestrator.result.StreamedResult` reads the folder back (whose name is
:data:`quadcosim.orchestrator.result.FOLDER`): a signal is gathered from the chunks when asked for, so that
a report reads one signal at a time.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from quadcosim.infra.files import atomic_path, write_json

#: Bytes of the window of rows held in memory before they go to disk.
WINDOW_BYTES = 8 * 2 ** 20

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
