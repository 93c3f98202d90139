"""A magnetometer calibration and its JSON file.

File format (UTF-8 JSON, SI units; every field is checked on loading)::

    {
      "format": "quadcosim-magnetometer-calibration",
      "version": 1,
      "motors": 4,                                  # N
      "static": {"A": [[3 x 3]], "b_s": [3],         # m_bar = A m + b_s (b_s in T)
                 "field_norm": 4.7e-05},             # |A^-1 (m_bar - b_s)| (T)
      "reference": [3],                             # m0, motors off (T), or null
      "field": {"orders": {"I": 4, "J": 1},          # eq. 4
                "v": [[N x 3]],                      # unit directions, sensor frame
                "theta": [[N x I (J + 1)]]},         # a_10, a_11, a_20, ... a_IJ (T / V^j)
      "dynamics": {"rate": 1/s, "drag": 1/(V s), "limit": V or null (none), "exponent": 0 | 1,
                   "freewheel": true | false, "gain": [N] (T/V)},
      "notes": {...}                                # free-form provenance
    }

``static``, ``reference``, ``field`` and ``dynamics`` may each be ``null``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from dataclasses import field as _default
from pathlib import Path

import numpy as np
from quadcosim.calibration.dynamic import MotorFieldModel
from quadcosim.calibration.identify import MotorDynamics
from quadcosim.calibration.static import CalibrationError, StaticCalibration

FORMAT = "quadcosim-magnetometer-calibration"
#: The largest calibration file read (bytes): one holds a few kB of coefficients.
MAX_CALIBRATION_BYTES = 16_000_000
VERSION = 1


SINGULAR = 1e-12  # |det A| below this times its largest entry cubed: singular


@dataclass
class Calibration:
    """Static calibration, the paper's motor-field model and the identified motor dynamics.

    Attributes
    ----------
    motors : int
        Number of motors N.
    static : StaticCalibration or None
        Soft and hard iron; ``None`` is ``A = I``, ``b_s = 0``.
    field : MotorFieldModel or None
        Directions ``v_n`` and amplitudes ``theta_n`` (eqs. 3, 4).
    dynamics : MotorDynamics or None
        For the dynamics-aware compensation.
    reference : (3,) array or None
        ``m0``, motors off, drone clamped (T).
    notes : dict
        Provenance, written as is.
    """

    motors: int = 4
    static: StaticCalibration | None = None
    field: MotorFieldModel | None = None
    dynamics: MotorDynamics | None = None
    reference: np.ndarray | None = None
    notes: dict = _default(default_factory=dict)

    def to_dict(self) -> dict:
        """The calibration as the JSON object of the file format (lists of floats, SI units)."""
        s, f, d = self.static, self.field, self.dynamics
        return {
            "format": FORMAT,
            "version": VERSION,
            "motors": self.motors,
            "static": None if s is None else {"A": np.asarray(s.A).tolist(), "b_s": np.asarray(s.b_s).tolist(),
                                              "field_norm": float(s.field_norm)},
            "reference": None if self.reference is None else np.asarray(self.reference, dtype=float).tolist(),
            "field": None if f is None else {"orders": {"I": f.orders[0], "J": f.orders[1]}, "v": f.v.tolist(),
                                             "theta": f.theta.tolist()},
            "dynamics": None if d is None else {"rate": d.rate, "drag": d.drag,
                                                "limit": d.limit if np.isfinite(d.limit) else None,
                                                "exponent": d.exponent, "freewheel": d.freewheel,
                                                "gain": np.asarray(d.gain).tolist()},
            "notes": self.notes,
        }

    def save(self, path) -> Path:
        """Write the calibration to ``path`` (JSON, atomically: :func:`quadcosim.infra.files.atomic_path`)
        and return the path."""
        from quadcosim.infra.files import write_text

        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        return write_text(path, json.dumps(self.to_dict(), indent=2) + "\n")

    @classmethod
    def from_dict(cls, data: dict, motors: int | None = None, orders: tuple[int, int] | None = None,
                  where: str = "calibration") -> Calibration:
        """The calibration held by a decoded file, checked field by field.

        Parameters
        ----------
        data : dict
            The decoded JSON object (see the module docstring).
        motors : int, optional
            Number of motors the vehicle has; a file for another number is refused.
        orders : (int, int), optional
            Orders ``(I, J)`` expected; a file with others is refused.
        where : str
            Name of the source (the file's path) in error messages.

        Raises
        ------
        CalibrationError
            Naming the defective field and what it should hold.
        """
        reader = _Reader(where)
        if not isinstance(data, dict):
            reader.fail("the file must hold a JSON object")
        if data.get("format") != FORMAT:
            reader.fail(f"not a magnetometer calibration (format {data.get('format')!r}, expected {FORMAT!r})")
        if data.get("version") != VERSION:
            reader.fail(f"version {data.get('version')!r} is not supported (this reader knows version {VERSION})")
        missing = [k for k in ("motors", "static", "reference", "field", "dynamics") if k not in data]
        if missing:
            reader.fail(f"missing key(s) {', '.join(missing)}")
        n = data["motors"]
        if not isinstance(n, int) or isinstance(n, bool) or n < 1:
            reader.fail(f"motors = {n!r} must be a positive integer")
        if motors is not None and n != motors:
            reader.fail(f"the file calibrates {n} motors; this vehicle has {motors}. Calibrate this vehicle")
        reference = None if data["reference"] is None else reader.array(data["reference"], (3,), "reference")
        notes = data.get("notes")
        if notes is not None and not isinstance(notes, dict):
            reader.fail(f"notes = {notes!r} must be a JSON object (or absent)")
        return cls(n, reader.static(data["static"]), reader.field(data["field"], n, orders),
                   reader.dynamics(data["dynamics"], n), reference, dict(notes or {}))

    @classmethod
    def load(cls, path, motors: int | None = None, orders: tuple[int, int] | None = None) -> Calibration:
        """Read the calibration file at ``path`` (JSON); refuse a malformed one, or one for another
        number of motors or other orders (when ``motors`` or ``orders`` is given), with a message
        naming the defect."""
        from quadcosim.infra.inputs import regular_file

        path = Path(path)
        fix = "give the JSON file `quadcosim run metge` or Calibration.save writes"
        size = regular_file(path, "the calibration file", fix, CalibrationError).st_size
        if size > MAX_CALIBRATION_BYTES:
            raise CalibrationError(f"{path}: {size / 1e6:.0f} MB, not a calibration file (at most "
                                   f"{MAX_CALIBRATION_BYTES / 1e6:.0f} MB); {fix}")
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as error:
            raise CalibrationError(f"cannot read calibration file {path}: {error.strerror}") from None
        except UnicodeDecodeError as error:
            raise CalibrationError(f"{path}: not UTF-8 text (byte 0x{error.object[error.start]:02x} at offset "
                                   f"{error.start}); a calibration file is JSON, as `quadcosim run metge` or "
                                   "Calibration.save writes it") from None
        try:
            data = json.loads(text)
        except json.JSONDecodeError as error:
            raise CalibrationError(f"{path}: not valid JSON ({error.msg} at line {error.lineno})") from None
        except RecursionError:
            raise CalibrationError(f"{path}: JSON nested too deeply to be a calibration file") from None
        return cls.from_dict(data, motors, orders, where=str(path))


class _Reader:
    """Checks of the parts of a calibration file; every refusal names the source and the field."""

    def __init__(self, where: str):
        self.where = where

    def fail(self, message: str):
        raise CalibrationError(f"{self.where}: {message}")

    def array(self, value, shape: tuple, name: str) -> np.ndarray:
        try:
            out = np.asarray(value, dtype=float)
        except (TypeError, ValueError, RecursionError):
            self.fail(f"{name} must be numbers, not {str(value)[:80]}")
        if out.shape != shape:
            self.fail(f"{name} must have shape {shape}, not {out.shape}")
        if not np.isfinite(out).all():
            self.fail(f"{name} holds NaN or Inf")
        return out

    def static(self, s) -> StaticCalibration | None:
        if s is None:
            return None
        if not isinstance(s, dict) or not {"A", "b_s", "field_norm"} <= set(s):
            self.fail("static must hold A, b_s and field_norm")
        A = self.array(s["A"], (3, 3), "static.A")
        largest = np.abs(A).max()
        if not largest > 0 or abs(np.linalg.det(A)) < SINGULAR * largest**3:
            self.fail("static.A is singular (all zeros, or rows that depend on each other); it must be invertible")
        field_norm = float(self.array(s["field_norm"], (), "static.field_norm"))
        if not field_norm > 0:
            self.fail(f"static.field_norm = {field_norm!r} must be positive (the corrected field's norm)")
        return StaticCalibration(A=A, b_s=self.array(s["b_s"], (3,), "static.b_s"), field_norm=field_norm)

    def field(self, f, n: int, orders) -> MotorFieldModel | None:
        if f is None:
            return None
        if not isinstance(f, dict) or not {"orders", "v", "theta"} <= set(f):
            self.fail("field must hold orders, v and theta")
        o = f["orders"]
        if not (isinstance(o, dict) and isinstance(o.get("I"), int) and isinstance(o.get("J"), int)
                and o["I"] >= 1 and o["J"] >= 0):
            self.fail(f"field.orders = {o!r} must be {{'I': integer >= 1, 'J': integer >= 0}}")
        I, J = o["I"], o["J"]
        if orders is not None and (I, J) != tuple(orders):
            self.fail(f"the file has orders I = {I}, J = {J}; ({orders[0]}, {orders[1]}) were asked for")
        v = self.array(f["v"], (n, 3), "field.v")
        if np.abs(np.linalg.norm(v, axis=1) - 1.0).max() > 1e-6:
            self.fail("field.v must hold unit vectors")
        theta = self.array(f["theta"], (n, I * (J + 1)), f"field.theta (orders I = {I}, J = {J})")
        return MotorFieldModel(v, theta, (I, J))

    def dynamics(self, d, n: int) -> MotorDynamics | None:
        if d is None:
            return None
        keys = {"rate", "drag", "limit", "exponent", "freewheel", "gain"}
        if not isinstance(d, dict) or not keys <= set(d):
            self.fail(f"dynamics must hold {', '.join(sorted(keys))}")
        rate, drag = (float(self.array(d[k], (), f"dynamics.{k}")) for k in ("rate", "drag"))
        limit = np.inf if d["limit"] is None else float(self.array(d["limit"], (), "dynamics.limit"))
        if not (rate > 0 and drag >= 0 and limit > 0):
            self.fail("dynamics.rate and dynamics.limit must be positive and dynamics.drag non-negative")
        if d["exponent"] not in (0, 1) or not isinstance(d["freewheel"], bool):
            self.fail("dynamics.exponent must be 0 or 1 and dynamics.freewheel true or false")
        return MotorDynamics(rate, drag, limit, int(d["exponent"]), d["freewheel"],
                             self.array(d["gain"], (n,), "dynamics.gain"))
