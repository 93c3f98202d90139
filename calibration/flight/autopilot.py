"""The autopilots a flight calibration exports for, as their registry gives them
(:mod:`quadcosim.flightlogs.autopilots`: each autopilot one folder carrying its firmware arithmetic
and its parameter writer, one line in the entry-point group ``quadcosim.autopilots``), and the
reading of a parameter file, ArduPilot's (``NAME,VALUE`` lines, as Mission Planner loads them) or
PX4's (QGroundControl's tab-separated format), for scoring one.
"""

from __future__ import annotations

from pathlib import Path


def autopilot_of(part):
    """The :class:`quadcosim.flightlogs.autopilots.Autopilot` of ``part``'s log (``part``: a
    :class:`quadcosim.calibration.flight.data.FlightData`)."""
    from quadcosim.flightlogs.autopilots import of

    return of(part.log.autopilot)


def write_parameters(autopilot: str, params: dict, path) -> None:
    """``params`` in the file format of ``autopilot`` (an installed autopilot's name) at ``path``."""
    from quadcosim.flightlogs.autopilots import of

    of(autopilot).write(params, path)


FLOAT32_MAX = 3.4028234663852886e38  # the largest value of the autopilots' 32-bit float parameters
MAX_PARAMETER_BYTES = 16 * 1024 * 1024  # an autopilot's whole parameter list takes a few hundred kB


def _shared_line(line: str) -> tuple[str, str]:
    """The name and value of an ArduPilot (``NAME,VALUE``, ``NAME VALUE``) or QGroundControl
    (``1<TAB>1<TAB>NAME<TAB>VALUE<TAB>TYPE``) line; ValueError or IndexError for a line holding none."""
    parts = line.split("\t") if "\t" in line else line.split(",") if "," in line else line.split()
    name, value = (parts[2], parts[3]) if len(parts) > 3 else parts[:2]
    return name, value


def read_parameters(path, autopilot=None) -> dict:
    """Parameters from an ArduPilot ``.parm`` (``NAME,VALUE`` or ``NAME VALUE`` lines) or a
    QGroundControl ``.params`` file (tab-separated) at ``path``, as the ArduPilot and PX4
    autopilots write them (:mod:`quadcosim.flightlogs.autopilots`), or, for an ``autopilot``
    (:class:`quadcosim.flightlogs.autopilots.Autopilot`) with a ``parameter_line`` of its own, its
    own file's lines.

    Raises
    ------
    ValueError
        The file is missing, not a regular file (a FIFO would block), too large, not text, or a
        line holds no ``NAME VALUE``; the message names the file, the line and the fix.
    """
    from quadcosim.infra.inputs import regular_file

    path = Path(path)
    status = regular_file(path, "the parameter file", "give a parameter file (.parm or .params)")
    if status.st_size > MAX_PARAMETER_BYTES:
        raise ValueError(f"{path}: {status.st_size / 1e6:.0f} MB, not a parameter file (.parm or .params)")
    try:
        text = path.read_text(encoding="utf-8-sig")  # a byte-order mark is not part of the first name
    except UnicodeDecodeError as error:
        raise ValueError(f"{path}: not a text parameter file (byte {error.start} is not UTF-8); give the .parm or "
                         ".params the ground station saved") from None
    except OSError as error:
        raise ValueError(f"{path}: cannot read the parameter file ({error.strerror})") from None
    own = getattr(autopilot, "parameter_line", None)
    parse = own or _shared_line
    form = (f"a line of {autopilot.name}'s parameter file ({autopilot.file})" if own else
            "NAME,VALUE (ArduPilot) nor 1<TAB>1<TAB>NAME<TAB>VALUE<TAB>TYPE (QGroundControl)")
    params = {}
    for number, line in enumerate(text.splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        try:
            name, value = parse(line)
            given = int(value) if value.strip().lstrip("-").isdigit() else float(value)
        except (ValueError, IndexError):
            raise ValueError(f"{path}, line {number}: {line[:60]!r} is not {form}; fix or remove the line") from None
        if name.strip() in params:
            raise ValueError(f"{path}, line {number}: {name.strip()} is given a second time; an autopilot keeps one "
                             "value per name: remove one of the lines")
        params[name.strip()] = given
        if not abs(params[name.strip()]) <= FLOAT32_MAX:  # NaN and infinities too
            raise ValueError(f"{path}, line {number}: {name.strip()} = {value.strip()} is not a value an autopilot "
                             "stores (its parameters are finite 32-bit floats); fix or remove the line")
    if not params:
        raise ValueError(f"{path}: no parameters in the file; give the .parm or .params the ground station saved")
    return params
