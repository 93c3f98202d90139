"""How a result's values are written into its files: the text of a CSV cell, and the forms
MATLAB holds."""

from __future__ import annotations

import numpy as np


def integer_text(value) -> str:
    """A CSV cell of an integer or Boolean signal's value (a float64 holding it): ``"3"``, ``"1"``."""
    return str(int(value))


def float_text(value) -> str:
    """A CSV cell of a float signal's value, every digit kept (``repr``)."""
    return repr(float(value))


def matlab_values(values: dict) -> dict:
    """``values`` as MATLAB can hold them: None as an empty string, lists of text as cell
    arrays, ``IMU.gyro_bias`` keys as ``IMU_gyro_bias`` (a field name holds no dot)."""
    plain = {}
    for key, value in values.items():
        key = str(key).replace(".", "_")
        if value is None:
            value = ""
        elif isinstance(value, dict):
            value = matlab_values(value)
        elif isinstance(value, list | tuple) and any(isinstance(v, str) for v in value):
            value = np.array([str(v) for v in value], dtype=object)
        plain[key] = value
    return plain
