"""Parameter files: ArduPilot's (``NAME,VALUE`` lines, as Mission Planner loads them) and PX4's
(QGroundControl's tab-separated format). The parameters themselves, and how each firmware applies
them, are in :mod:`orchestrator.logs.ardupilot` and :mod:`orchestrator.logs.px4`.
"""

from __future__ import annotations

from pathlib import Path


def write_ardupilot(params: dict, path) -> None:
    """``params`` as an ArduPilot parameter file (``NAME,VALUE`` lines, as Mission Planner loads) at ``path``."""
    with open(path, "w") as file:
        for name, value in params.items():
            file.write(f"{name},{value:.9g}\n")


def write_px4(params: dict, path) -> None:
    """``params`` as a QGroundControl parameter file for PX4 (tab-separated, vehicle 1) at ``path``."""
    with open(path, "w") as file:
        file.write("# Vehicle-Id Component-Id Name Value Type\n")
        for name, value in params.items():
            kind = 6 if isinstance(value, int) else 9  # MAV_PARAM_TYPE_INT32, REAL32
            file.write(f"1\t1\t{name}\t{value:.9g}\t{kind}\n")


def write_parameters(autopilot: str, params: dict, path) -> None:
    """``params`` in the file format of ``autopilot`` (``ArduPilot`` or ``PX4``) at ``path``."""
    (write_px4 if autopilot == "PX4" else write_ardupilot)(params, path)


def read_parameters(path) -> dict:
    """Parameters from a file written by :func:`write_ardupilot` or :func:`write_px4` at ``path``."""
    params = {}
    for line in Path(path).read_text().splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        parts = line.split("\t") if "\t" in line else line.split(",") if "," in line else line.split()
        name, value = (parts[2], parts[3]) if len(parts) > 3 else parts[:2]
        params[name] = int(value) if value.lstrip("-").isdigit() else float(value)
    return params
