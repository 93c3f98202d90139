"""Findings of what a run's record costs: its files on the disk, and memory when it is streamed.

- ``quadcosim run tp`` (its default ``20`` s) prints ``results_npz_mb``, the size of the
  ``results.npz`` it wrote (``metrics.json`` records it); ``--compress`` the compressed one's;
- ``python -m quadcosim.benchmarks.save --stream-peak`` prints the peak resident memory of ``tp`` runs of
  60 s and 3600 s written with ``--stream``, and their ratio. Memory depends on the machine and
  the libraries' versions: the tolerance says so, and these are never re-checked in CI (the
  3600 s run takes minutes).
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from findings import finding

RUN = "quadcosim run tp"
STREAM = "python -m quadcosim.benchmarks.save --stream-peak"
SIZE_TOLERANCE_MB = 0.05  # MB: the uncompressed record is 8 bytes a value, its size fixed by the run
COMPRESSED_TOLERANCE_MB = 0.2  # MB: compression depends on the values' last bits and on zlib's version
PEAK_TOLERANCE_MB = 50.0  # MB: resident memory moves with the machine, numpy, numba and whether its cache is warm
RATIO_TOLERANCE = 0.1  # 1: 1.11 to 1.14 in three runs on one machine


def record_size(compress: bool) -> float:
    """Size (MB) of the ``results.npz`` of ``quadcosim run tp`` (with ``--compress`` if ``compress``)."""
    from quadcosim import scenarios

    with tempfile.TemporaryDirectory() as folder:
        _, metrics = scenarios.run("tp", {}, Path(folder) / "tp", compress=compress)
    return metrics["results_npz_mb"]


def compute(quick: bool = False) -> list[dict]:
    """The record findings; ``quick``: the uncompressed size alone (one ``20`` s ``tp`` run)."""
    found = [finding("records.tp_npz_mb", record_size(False), "MB", RUN, SIZE_TOLERANCE_MB, 1)]
    if quick:
        return found
    from quadcosim.benchmarks.save import stream_peak

    found.append(finding("records.tp_npz_compressed_mb", record_size(True), "MB", f"{RUN} --compress",
                         COMPRESSED_TOLERANCE_MB, 1))
    peak = stream_peak()
    shortest, longest = min(peak["peak_mb"]), max(peak["peak_mb"])
    return found + [finding("records.stream_peak.long_mb", peak["peak_mb"][longest], "MB", STREAM,
                            PEAK_TOLERANCE_MB, 0),
                    finding("records.stream_peak.short_mb", peak["peak_mb"][shortest], "MB", STREAM,
                            PEAK_TOLERANCE_MB, 0),
                    finding("records.stream_peak.ratio", peak["ratio"], "1", STREAM, RATIO_TOLERANCE, 2)]
