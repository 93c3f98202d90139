"""A setpoint profile read from a CSV file (``quadcosim run tp --set flight=my_flight.csv``).

The file has a header row and one row per time, for example::

    t,theta_d1_deg,theta_d2_deg,theta_d3_deg,z_d
    0,0,0,0,0
    5,10,0,0,-1
    10,0,0,45,-1

- ``t`` (s): strictly increasing times; before the first row the first row holds, after the
  last the last.
- any of :data:`quadcosim.flight.SETPOINT`: ``theta_d1, theta_d2, theta_d3`` (roll, pitch, yaw,
  rad; or in degrees with the suffix ``_deg``), ``x_d, y_d, z_d`` (m, NED: up is negative),
  ``hold`` (1: hold the horizontal position ``x_d, y_d``; 0: fly the roll and pitch
  setpoints). A column left out is 0.
- Between rows the setpoints are interpolated linearly; ``hold`` switches at its row.

The vehicle starts at rest, level, at the origin.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
from quadcosim.orchestrator.fmu import nearest

TIME_COLUMN = "t"
MAX_PROFILE_BYTES = 100_000_000  # a profile is a table of setpoints, not a recording
BYTES_PER_MB = 1_000_000  # for the size in the refusal
ANGLES = ("theta_d1", "theta_d2", "theta_d3")
DEGREE_SUFFIX = "_deg"
RAD_PER_DEG = math.pi / 180.0  # rad per degree, for the columns given in degrees


def is_profile_file(flight: str) -> bool:
    """Whether a ``flight`` option names a CSV file rather than a built-in profile."""
    return str(flight).lower().endswith(".csv")


def _columns(setpoint: tuple) -> dict:
    """Accepted column name -> (setpoint index, factor to SI)."""
    columns = {name: (i, 1.0) for i, name in enumerate(setpoint)}
    columns |= {name + DEGREE_SUFFIX: (setpoint.index(name), RAD_PER_DEG) for name in ANGLES}
    return columns


def read_profile(path: str | Path, setpoint: tuple) -> tuple[np.ndarray, np.ndarray]:
    """The times and setpoint rows of a profile file.

    Parameters
    ----------
    path : str or pathlib.Path
        The CSV file (format in the module docstring).
    setpoint : tuple of str
        The setpoint's names, in the order of the rows returned.

    Returns
    -------
    times : (n,) ndarray
        s.
    rows : (n, len(setpoint)) ndarray
        SI units.

    Raises
    ------
    ValueError
        A missing file, text that is not UTF-8, an unknown or repeated column (the nearest names
        offered), an angle given twice (in rad and in deg), no ``t`` column, a value that is not
        a finite number, or times not strictly increasing; the message names the file, row and
        column.
    """
    from quadcosim.infra.inputs import regular_file

    path = Path(path)
    if not path.exists() and not path.is_symlink():
        raise ValueError(f"flight={path}: no such file (a setpoint profile is a CSV file with a header row; "
                         "see flight/profile_file.py)")
    size = regular_file(path, "the setpoint profile", "a setpoint profile is a CSV file with a header row",
                        label=f"flight={path}").st_size
    if size > MAX_PROFILE_BYTES:
        raise ValueError(f"flight={path}: {size / BYTES_PER_MB:.0f} MB, not a setpoint profile (a CSV "
                         f"of at most {MAX_PROFILE_BYTES / BYTES_PER_MB:.0f} MB)")
    try:
        # utf-8-sig: a spreadsheet's "CSV UTF-8" begins with a byte-order mark, not part of the header
        with path.open(newline="", encoding="utf-8-sig") as handle:
            table = list(csv.reader(handle))
    except UnicodeDecodeError as error:
        raise ValueError(f"{path}: not UTF-8 text (byte {error.object[error.start]:#04x} at byte {error.start}, a "
                         "Latin-1 or Windows character?); save the file as UTF-8") from None
    except (OSError, csv.Error) as error:
        raise ValueError(f"{path}: not a readable CSV file ({error})") from None
    header, body = [name.strip() for name in table[0]] if table else [], [r for r in table[1:] if any(r)]
    columns = _columns(setpoint)
    for name in header:
        if name != TIME_COLUMN and name not in columns:
            raise ValueError(f"{path}: unknown column {name!r}.{nearest(name, [TIME_COLUMN, *columns])} "
                             f"Columns: {TIME_COLUMN} (s), {', '.join(columns)}.")
    if len(set(header)) != len(header) or TIME_COLUMN not in header or not body:
        raise ValueError(f"{path}: needs a header with the time column {TIME_COLUMN!r} (s), each column once, "
                         "and at least one row")
    twice = [name for name in ANGLES if name in header and name + DEGREE_SUFFIX in header]
    if twice:
        raise ValueError(f"{path}: {', '.join(f'{n} and {n}{DEGREE_SUFFIX}' for n in twice)} give one angle twice "
                         "(rad and deg); keep one of the two columns")
    values = np.empty((len(body), len(header)))
    for row_number, row in enumerate(body, start=2):
        if len(row) != len(header):
            raise ValueError(f"{path}, row {row_number}: {len(row)} values for {len(header)} columns")
        for j, text in enumerate(row):
            try:
                values[row_number - 2, j] = float(text)
            except ValueError:
                values[row_number - 2, j] = math.nan
            if not math.isfinite(values[row_number - 2, j]):
                raise ValueError(f"{path}, row {row_number}, column {header[j]}: {text!r} is not a finite number")
    times = values[:, header.index(TIME_COLUMN)]
    if np.any(np.diff(times) <= 0):
        raise ValueError(f"{path}: the times ({TIME_COLUMN}) must increase strictly from row to row")
    rows = np.zeros((len(times), len(setpoint)))
    for j, name in enumerate(header):
        if name != TIME_COLUMN:
            index, factor = columns[name]
            rows[:, index] = values[:, j] * factor
    return times, rows


class FileProfile:
    """A profile file as a function of time, as the ``Setpoint`` table evaluates it.

    Parameters
    ----------
    path : str or pathlib.Path
        The CSV file (format in the module docstring).
    setpoint : tuple of str
        The setpoint's names; a column named ``hold`` is held, not interpolated.
    """

    def __init__(self, path, setpoint: tuple):
        self.path = Path(path)
        self.times, self.rows = read_profile(path, setpoint)
        self.held = [i for i, name in enumerate(setpoint) if name == "hold"]

    def __call__(self, t: np.ndarray) -> np.ndarray:
        """Setpoint rows at times ``t`` (s): an array of shape ``(len(t), len(setpoint))``."""
        t = np.asarray(t, dtype=float)
        out = np.column_stack([np.interp(t, self.times, column) for column in self.rows.T])
        if self.held:
            at = np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, len(self.times) - 1)
            out[:, self.held] = self.rows[at][:, self.held]
        return out
