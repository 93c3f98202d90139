"""Findings of the ArduCopter 3.6 and 4.3 logs: each compass's exported parameter file and the log
as flown, scored on the score part as the log's firmware applies them (heading error, deg RMS).

``copter43_cubeorange.bin`` (ArduCopter 4.3.6 on a CubeOrange: an external compass rotated by
``COMPASS_ORIENT = 6`` with ``COMPASS_SCALE``, an internal one unused and never calibrated) with
its last half held out, as the flight-logs guide calibrates it; ``copter36_three_compasses.bin``
(ArduCopter 3.6.7, three compasses, cut at its logging stall and crash) with the default split.
The logs are read from ``$QUADCOSIM_FLIGHT_LOGS`` (see :mod:`findings.flightlogs`); without it
the group is skipped. The quick subset is copter43's two compasses (seconds each).
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import tempfile
from pathlib import Path

from findings import finding

FOLDER_VARIABLE = "QUADCOSIM_FLIGHT_LOGS"
# (key, file, compass, --test-fraction or None)
EXPORTS = [("copter43", "copter43_cubeorange.bin", 0, 0.5), ("copter43", "copter43_cubeorange.bin", 1, 0.5),
           ("copter36", "copter36_three_compasses.bin", 0, None), ("copter36", "copter36_three_compasses.bin", 1, None),
           ("copter36", "copter36_three_compasses.bin", 2, None)]
TOLERANCE_DEG = 0.02  # the command prints 2 decimals


def _path(name: str) -> Path:
    folder = os.environ.get(FOLDER_VARIABLE)
    if not folder:
        raise FileNotFoundError(f"the flight logs are absent: set {FOLDER_VARIABLE} to their folder")
    found = Path(folder) / name
    if not found.exists():
        raise FileNotFoundError(f"{found}: the flight log is absent from {FOLDER_VARIABLE}")
    return found


def _arguments(name: str, compass: int, fraction) -> list[str]:
    return [name, "--compass", str(compass), *([] if fraction is None else ["--test-fraction", f"{fraction:g}"])]


def export(key: str, name: str, compass: int, fraction) -> list[dict]:
    """The export of compass ``compass`` of the log ``name`` and the log as flown, on the score part."""
    from quadcosim.scenarios.flightlog.calibrate import main as calibrate

    with tempfile.TemporaryDirectory() as folder, contextlib.redirect_stdout(io.StringIO()), \
            contextlib.redirect_stderr(io.StringIO()):
        arguments = _arguments(str(_path(name)), compass, fraction)
        calibrate([*arguments, "--out", folder, "--overwrite"])
        metrics = json.loads((Path(folder) / "metrics.json").read_text())["export"]
    command = f"quadcosim calibrate {' '.join(_arguments(f'logs/{name}', compass, fraction))} --out results/flightlogs"
    prefix = f"ardupilot_logs.{key}.compass{compass}"
    return [finding(f"{prefix}.export_deg", metrics["heading_rms_deg"], "deg", command, TOLERANCE_DEG, 2),
            finding(f"{prefix}.as_flown_deg", metrics["as_flown"]["heading_rms_deg"], "deg", command,
                    TOLERANCE_DEG, 2)]


def compute(quick: bool = False) -> list[dict]:
    """The group's findings (see the module docstring); ``quick``: copter43's two compasses."""
    chosen = [e for e in EXPORTS if e[0] == "copter43"] if quick else EXPORTS
    return [f for entry in chosen for f in export(*entry)]
