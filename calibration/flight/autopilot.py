"""Parameter files: ArduPilot's (``NAME,VALUE`` lines, as Mission Planner loads them) and PX4's
(QGroundControl's tab-separated format). The parameters themselves, and how each firmware applies
them, are in :mod:`flightlogs.ardupilot` and :mod:`flightlogs.px4`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path


def write_ardupilot(params: dict, path) -> None:
    """``params`` as an ArduPilot parameter file (``NAME,VALUE`` lines, as Mission Planner loads) at
    ``path``, written atomically (:func:`orchestrator.files.atomic_path`)."""
    from orchestrator.files import write_text

    write_text(path, "".join(f"{name},{value:.9g}\n" for name, value in params.items()))


def write_px4(params: dict, path) -> None:
    """``params`` as a QGroundControl parameter file for PX4 (tab-separated, vehicle 1) at ``path``,
    written atomically (:func:`orchestrator.files.atomic_path`)."""
    from orchestrator.files import write_text

    lines = ["# Vehicle-Id Component-Id Name Value Type\n"]
    for name, value in params.items():
        kind = 6 if isinstance(value, int) else 9  # MAV_PARAM_TYPE_INT32, REAL32
        lines.append(f"1\t1\t{name}\t{value:.9g}\t{kind}\n")
    write_text(path, "".join(lines))


@dataclass(frozen=True)
class Autopilot:
    """An autopilot the export writes parameters for.

    Attributes
    ----------
    name : str
        As a flight log names it (:attr:`flightlogs.FlightLog.autopilot`).
    file : str
        The parameter file the export writes in the results folder.
    write : callable
        ``(params, path)``: the parameters in the autopilot's file format.
    """

    name: str
    file: str
    write: Callable[[dict, object], None]


#: The autopilots, one line each: a flight log of one of them is exported in its own file.
AUTOPILOTS = {autopilot.name: autopilot for autopilot in (
    Autopilot("ArduPilot", "ardupilot.parm", write_ardupilot),
    Autopilot("PX4", "px4.params", write_px4),
)}


def write_parameters(autopilot: str, params: dict, path) -> None:
    """``params`` in the file format of ``autopilot`` (a name of :data:`AUTOPILOTS`) at ``path``."""
    AUTOPILOTS[autopilot].write(params, path)


FLOAT32_MAX = 3.4028234663852886e38  # the largest value of the autopilots' 32-bit float parameters
MAX_PARAMETER_BYTES = 16 * 1024 * 1024  # an autopilot's whole parameter list takes a few hundred kB


def read_parameters(path) -> dict:
    """Parameters from an ArduPilot ``.parm`` (``NAME,VALUE`` or ``NAME VALUE`` lines) or a
    QGroundControl ``.params`` file (tab-separated) at ``path``, as :func:`write_ardupilot` and
    :func:`write_px4` write them.

    Raises
    ------
    ValueError
        The file is missing, not a regular file (a FIFO would block), too large, not text, or a
        line holds no ``NAME VALUE``; the message names the file, the line and the fix.
    """
    import os
    import stat

    path = Path(path)
    try:
        status = os.stat(path)
    except OSError as error:
        raise ValueError(f"{path}: cannot read the parameter file ({error.strerror})") from None
    if not stat.S_ISREG(status.st_mode):
        raise ValueError(f"{path}: not a regular file; give a parameter file (.parm or .params)")
    if status.st_size > MAX_PARAMETER_BYTES:
        raise ValueError(f"{path}: {status.st_size / 1e6:.0f} MB, not a parameter file (.parm or .params)")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as error:
        raise ValueError(f"{path}: not a text parameter file (byte {error.start} is not UTF-8); give the .parm or "
                         ".params the ground station saved") from None
    except OSError as error:
        raise ValueError(f"{path}: cannot read the parameter file ({error.strerror})") from None
    params = {}
    for number, line in enumerate(text.splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        parts = line.split("\t") if "\t" in line else line.split(",") if "," in line else line.split()
        try:
            name, value = (parts[2], parts[3]) if len(parts) > 3 else parts[:2]
            params[name.strip()] = int(value) if value.strip().lstrip("-").isdigit() else float(value)
        except (ValueError, IndexError):
            raise ValueError(f"{path}, line {number}: {line[:60]!r} is not NAME,VALUE (ArduPilot) nor "
                             "1<TAB>1<TAB>NAME<TAB>VALUE<TAB>TYPE (QGroundControl); fix or remove the line") from None
        if not abs(params[name.strip()]) <= FLOAT32_MAX:  # NaN and infinities too
            raise ValueError(f"{path}, line {number}: {name.strip()} = {value.strip()} is not a value an autopilot "
                             "stores (its parameters are finite 32-bit floats); fix or remove the line")
    if not params:
        raise ValueError(f"{path}: no parameters in the file; give the .parm or .params the ground station saved")
    return params
