"""What a flight log holds, in the project's conventions (NED, FRD body, SI units)."""

from __future__ import annotations

from dataclasses import dataclass
from dataclasses import field as _default

import numpy as np

from quadcosim.infra.errors import UsageError


class LogError(UsageError, ValueError):
    """A log that cannot be read or used; the message names the file, the defect and the fix."""


@dataclass(frozen=True)
class Compass:
    """One magnetometer instance.

    Attributes
    ----------
    name : str
        The log's name for it (``MAG2``, ``sensor_mag[1]``).
    time : (T,) array
        Sample times on the log's clock (s).
    field : (T, 3) array
        Field as the autopilot logged it, after its own corrections, body FRD (T).
    raw : (T, 3) array
        Field before the autopilot's offsets, soft iron and motor compensation, body FRD (T);
        what a calibration starts from.
    offsets : (3,) array
        Hard-iron offsets the autopilot used, in its own sign convention turned to ours:
        ``raw = A b_true + offsets`` (T).
    external : bool or None
        True for an external compass, None when the log does not say.
    raw_source : str
        How ``raw`` was obtained (logged raw topic, or the logged field with the logged
        corrections undone).
    soft_iron : (3, 3) array
        The autopilot's soft-iron correction in our convention, ``raw = soft_iron m + offsets``.
    rotation : (3, 3) array
        Body-from-sensor rotation of ``raw``: the identity where the log's raw field is already in
        the body frame (ArduPilot), ``CAL_MAGn_ROT`` or the board's rotation for PX4's sensor frame.
    slot : int
        The calibration parameters' index: ArduPilot's compass number, PX4's ``CAL_MAGn`` matched by
        ``CAL_MAGn_ID`` to the sensor's device id.
    unusable : str
        Why the raw field cannot be recovered (a singular soft-iron matrix in the log's
        parameters, named), or empty; ``raw`` is then NaN and the compass is refused for a
        calibration (:meth:`FlightLog.compass`).
    setup : dict
        How the autopilot is set up to use it, name: text, as ``log info`` prints it (ArduPilot:
        priority, use, orientation, scale, parameter slot, device id); empty when the reader says
        nothing.
    """

    name: str
    time: np.ndarray
    field: np.ndarray
    raw: np.ndarray
    offsets: np.ndarray
    external: bool | None = None
    raw_source: str = ""
    soft_iron: np.ndarray = _default(default_factory=lambda: np.eye(3))
    rotation: np.ndarray = _default(default_factory=lambda: np.eye(3))
    slot: int = 0
    unusable: str = ""
    setup: dict = _default(default_factory=dict)


@dataclass(frozen=True)
class Position:
    """Where and when the vehicle flew, from its GPS: ``latitude_deg``, ``longitude_deg`` (WGS 84),
    ``altitude_m`` (above mean sea level), ``year`` (decimal year, UTC) and ``source`` (the message)."""

    latitude_deg: float
    longitude_deg: float
    altitude_m: float
    year: float
    source: str


@dataclass(frozen=True)
class Throttle:
    """The throttle the autopilot's compass compensation uses: ``value`` (T,) (0..1) at ``time``
    (T,) (s); ``source`` names it (ArduPilot's ``CTUN.ThO``, PX4's thrust setpoint)."""

    time: np.ndarray
    value: np.ndarray
    source: str


@dataclass(frozen=True)
class Imu:
    """One IMU instance: ``gyro`` (T, 3) body rates (rad/s) and ``acc`` (T, 3) specific force
    (m/s^2), body FRD, at ``time`` (T,) (s); ``name`` is the log's name for it."""

    name: str
    time: np.ndarray
    gyro: np.ndarray
    acc: np.ndarray


@dataclass(frozen=True)
class Motors:
    """Motor outputs: ``commands`` (T, N) normalised to 0..1 from the log's PWM limits
    ``pwm_min`` and ``pwm_max`` (us, named by ``limits_from``), ``pwm`` (T, N) as logged (us),
    at ``time`` (T,) (s)."""

    time: np.ndarray
    commands: np.ndarray
    pwm: np.ndarray
    pwm_min: float
    pwm_max: float
    limits_from: str

    @property
    def throttle(self) -> np.ndarray:
        """Collective throttle: the mean of the normalised commands (1), shape (T,)."""
        return self.commands.mean(axis=1)


@dataclass(frozen=True)
class Battery:
    """Battery ``voltage`` (T,) (V) and ``current`` (T,) (A, None without a current sensor) at
    ``time`` (T,) (s); ``current_sensor`` says why the current is or is not trusted."""

    time: np.ndarray
    voltage: np.ndarray
    current: np.ndarray | None
    current_sensor: str


@dataclass(frozen=True)
class Attitude:
    """The autopilot's attitude estimate: quaternion ``q`` (T, 4), scalar first, body FRD to
    NED, at ``time`` (T,) (s); ``source`` names the message or topic."""

    time: np.ndarray
    q: np.ndarray
    source: str


@dataclass
class FlightLog:
    """Everything quadcosim reads from one flight log (PX4 ULog, ArduPilot DataFlash or another
    installed autopilot's).

    Attributes
    ----------
    path : str
        The file.
    format : str
        The name of the log's format (``ulog``, ``dataflash-binary``, ``dataflash-text``: a
        :class:`quadcosim.flightlogs.autopilots.LogFormat` of its autopilot).
    autopilot : str
        The name of the installed autopilot that wrote it (``PX4``, ``ArduPilot``:
        :func:`quadcosim.flightlogs.autopilots.registry`).
    firmware : str
        Firmware name and version as the log states it.
    vehicle : str
        Vehicle type (``quadrotor``...).
    simulator : bool
        True for a simulator (SITL) log.
    compasses, imus : list
        Every :class:`Compass` and :class:`Imu` instance, in the log's order.
    motors : Motors or None
    battery : Battery or None
    attitude : Attitude or None
    params : dict
        The log's parameters (name: value), as the autopilot names them.
    position : Position or None
        The GPS fix the Earth field model is evaluated at (None without a GPS fix).
    throttle : Throttle or None
        The autopilot's own throttle signal, the one its compass compensation multiplies.
    warnings : list of str
        What was found wrong but could be read past (corruption skipped, a truncated end), and what
        was cut off (a crash, a logging stall: :mod:`quadcosim.flightlogs.trim`).
    defaults : dict
        The firmware's default of each parameter where the log states it (ArduPilot 4.x's
        ``PARM.Default``), name: value; empty otherwise.
    synthetic : str
        The log's own statement that it is synthetic (a message starting with
        :data:`SYNTHETIC_MARK`, which ``quadcosim log example`` writes), or empty for a recording.
    """

    path: str
    format: str
    autopilot: str
    firmware: str
    vehicle: str
    simulator: bool
    compasses: list[Compass] = _default(default_factory=list)
    imus: list[Imu] = _default(default_factory=list)
    motors: Motors | None = None
    battery: Battery | None = None
    attitude: Attitude | None = None
    params: dict = _default(default_factory=dict)
    warnings: list[str] = _default(default_factory=list)
    position: Position | None = None
    throttle: Throttle | None = None
    defaults: dict = _default(default_factory=dict)
    synthetic: str = ""

    @property
    def start(self) -> float:
        """First sample time of any sensor (s)."""
        return min(s.time[0] for s in self._series() if len(s.time))

    @property
    def duration(self) -> float:
        """Time from the first to the last sensor sample (s)."""
        return max(s.time[-1] for s in self._series() if len(s.time)) - self.start

    def _series(self):
        return [*self.compasses, *self.imus, *(x for x in (self.motors, self.battery, self.attitude) if x)]

    def compass(self, index: int) -> Compass:
        """Compass ``index``, counted from 0 in the log's order; a clear error if absent."""
        if not self.compasses:
            carrier = self._autopilot()
            raise LogError(f"{self.path}: the log holds no magnetometer; log one ({carrier.messages['compass']}, "
                           f"chosen by {carrier.logging}) to calibrate it")
        if not 0 <= index < len(self.compasses):
            names = ", ".join(f"{k}: {c.name}" for k, c in enumerate(self.compasses))
            raise LogError(f"{self.path}: no compass {index}; the log holds {names}")
        chosen = self.compasses[index]
        if chosen.unusable:
            others = [str(k) for k, c in enumerate(self.compasses) if not c.unusable]
            hint = f"; use another compass (--compass {' or '.join(others)})" if others else ""
            raise LogError(f"{self.path}: compass {index} ({chosen.name}): {chosen.unusable}{hint}")
        return chosen

    def require(self, purpose: str, *parts: str):
        """Refuse a log that lacks a part ``purpose`` needs, naming the messages (or topics) of its
        autopilot that carry it.

        Parameters
        ----------
        purpose : str
            What needs them (``"a replay"``), for the message.
        *parts : str
            Among ``"compass"``, ``"imu"``, ``"attitude"``, ``"motors"``, ``"battery"``.

        Raises
        ------
        LogError
            The parts missing, each with the message types that carry it.
        """
        present = {"compass": bool(self.compasses), "imu": bool(self.imus), "attitude": self.attitude is not None,
                   "motors": self.motors is not None, "battery": self.battery is not None}
        missing = [part for part in parts if not present[part]]
        if missing:
            carrier = self._autopilot()
            named = "; ".join(f"{PARTS[part]} ({carrier.messages[part]})" for part in missing)
            raise LogError(f"{self.path}: {purpose} needs what the log does not hold: {named}. Log them "
                           f"({carrier.logging}) or give another log")

    def _autopilot(self):
        """The installed autopilot that wrote the log (:mod:`quadcosim.flightlogs.autopilots`)."""
        from quadcosim.flightlogs.autopilots import of

        return of(self.autopilot)

    def overlap(self, *series) -> tuple[float, float]:
        """The span of time (s) that every one of ``series`` covers (objects with a ``time``).

        Raises
        ------
        LogError
            They share no span: each one's span is named (time stamps shifted, or two logs joined).
        """
        named = [(name, s.time) for name, s in series if s is not None and len(s.time)]
        lo, hi = max(t[0] for _, t in named), min(t[-1] for _, t in named)
        if hi <= lo:
            spans = ", ".join(f"{name} {t[0]:.1f} to {t[-1]:.1f} s" for name, t in named)
            raise LogError(f"{self.path}: its sensors share no span of time ({spans}): their time stamps do not "
                           "match (shifted, or parts of different logs); give a log whose sensors were recorded "
                           "together")
        return float(lo), float(hi)


#: How a synthetic log says so in its own text messages (ArduPilot ``MSG``): the start of the message.
SYNTHETIC_MARK = "synthetic flight: "  # no comma: a text log splits its fields on commas


def synthetic_statement(messages) -> str:
    """The first of the log's text ``messages`` (str) that starts with :data:`SYNTHETIC_MARK`, or ``""``."""
    return next((m for m in messages if str(m).startswith(SYNTHETIC_MARK)), "")


#: The parts of a log :meth:`FlightLog.require` names, each carried by the messages its autopilot's
#: ``messages`` name (:class:`quadcosim.flightlogs.autopilots.Autopilot`).
PARTS = {"compass": "a magnetometer", "imu": "an IMU", "attitude": "the attitude", "motors": "the motor outputs",
         "battery": "the battery"}


def rate(time: np.ndarray) -> float:
    """Mean sample rate (Hz) of increasing times ``time`` (s); 0 for fewer than two samples."""
    return (len(time) - 1) / (time[-1] - time[0]) if len(time) > 1 and time[-1] > time[0] else 0.0
