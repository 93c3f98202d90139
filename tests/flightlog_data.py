"""The real flight logs, read once per test session; tests that need them skip, saying why, when
the folder is absent.

One setting names the folder for the tests and the findings alike: ``$QUADCOSIM_FLIGHT_LOGS``
(:data:`findings.flightlogs.FOLDER_VARIABLE`), by default ``../shared/data/flightlogs`` beside the
repository."""

import os
from functools import cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DEFAULT = ROOT.parent / "shared" / "data" / "flightlogs"
FOLDER = Path(os.environ.get("QUADCOSIM_FLIGHT_LOGS") or DEFAULT)
QUAD = ("quad_2015-10-11_19-53-46.log", "quad_2015-10-11_19-59-09.log", "quad_2015-10-11_20-17-22.log")
ERLE = "erlebrain_APM_22.bin"
PX4 = "px4_sample.ulg"
COPTER43 = "copter43_cubeorange.bin"  # ArduCopter 4.3.6: instanced MAG, COMPASS_PRIOn_ID, COMPASS_SCALE
COPTER36 = "copter36_three_compasses.bin"  # ArduCopter 3.6.7: three compasses, a stall and a crash
#: Every shared ArduPilot log (a test over all of them reads this; the PX4 logs are listed apart).
ARDUPILOT = (*QUAD, ERLE, COPTER36, COPTER43)


def path(name: str) -> Path:
    """The shared log ``name``; skips the test when it is not there."""
    found = FOLDER / name
    if not found.exists():
        pytest.skip(f"real flight logs not found at {FOLDER} (set $QUADCOSIM_FLIGHT_LOGS to their folder)")
    return found


@cache
def _read(name: str):
    from quadcosim.flightlogs import read_log

    return read_log(FOLDER / name)


def log(name: str):
    """The :class:`quadcosim.flightlogs.FlightLog` of the shared log ``name``, read once."""
    path(name)
    return _read(name)
