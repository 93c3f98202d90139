"""One compass of one flight log, aligned for calibration: the raw field at its own sample
instants, the attitude that removes the Earth field there, and the interference regressors
(motor commands, throttle, battery current and voltage) that can be read at any instant, delayed.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from quadcosim.calibration.static import CalibrationError

ATTITUDES = ("auto", "gyro", "log")
#: Compass rate (Hz) a flight calibration needs. Measured by decimating the example flights a, b, c
#: (a current field of 0.4 -0.6 0.9 uT/A lagging 0.1 s; 40 s and 80 s long; the current model): at 10,
#: 5, 3.3 and 2.5 Hz every flight gives the delay exactly and the coefficients within 1.4 % of |K|; at
#: 2 Hz flight c's delay is off by 20 ms, at 1 Hz two flights' are and the coefficients drift to 2.3 %.
MIN_COMPASS_RATE_HZ = 2.5
MIN_SAMPLES = 40  # compass samples a flight (or a part of one) needs: 3 residuals each, and the per-motor
# model of an octorotor has 54 unknowns (6 of the flight, 2 direction angles and 4 coefficients a motor)


def euler_of(q: np.ndarray) -> np.ndarray:
    """Roll, pitch, yaw (rad, Z-Y-X; yaw unwrapped) of body-to-NED quaternions ``q`` (T, 4), scalar first."""
    from scipy.spatial.transform import Rotation

    euler = Rotation.from_quat(q, scalar_first=True).as_euler("ZYX")[:, ::-1].copy()
    euler[:, 2] = np.unwrap(euler[:, 2])
    return euler


def rotation_of(euler: np.ndarray) -> np.ndarray:
    """Body-to-NED rotation matrices (T, 3, 3) of roll, pitch, yaw ``euler`` (T, 3) (rad, Z-Y-X)."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_euler("ZYX", euler[:, ::-1]).as_matrix()


def board_quaternions(log, trim: bool = True) -> np.ndarray:
    """The attitude (T, 4) of the frame the autopilot's sensors are rotated into, at the log's
    attitude instants: ArduPilot's ``ATT`` is the vehicle's, the board's turned by ``AHRS_TRIM``,
    which is added back (the autopilot's ``board_trim``, :mod:`quadcosim.flightlogs.autopilots`); PX4 rotates its
    sensors into the vehicle's frame itself. ``trim=False`` ignores the trim (an ablation)."""
    from quadcosim.flightlogs.autopilots import of
    from scipy.spatial.transform import Rotation

    q = log.attitude.q
    board_trim = of(log.autopilot).board_trim
    if not trim or board_trim is None:
        return q
    board = Rotation.from_quat(q, scalar_first=True) * Rotation.from_matrix(board_trim(log.params))
    return board.as_quat(scalar_first=True)


def gyro_heading(log, times: np.ndarray, trim: bool = True) -> np.ndarray:
    """Heading (rad) at ``times`` (s) integrated from the first IMU's gyro, with the board's roll and
    pitch (:func:`board_quaternions`); its constant and its linear drift are matched to the log's
    heading over the whole flight, so no stretch shorter than the flight depends on the compass.
    ``log``: the FlightLog; ``trim``: add ``AHRS_TRIM`` back (False: an ablation)."""
    imu = log.imus[0]
    euler = euler_of(board_quaternions(log, trim))
    roll = np.interp(imu.time, log.attitude.time, euler[:, 0])
    pitch = np.interp(imu.time, log.attitude.time, euler[:, 1])
    p, q, r = imu.gyro.T
    rate = (q * np.sin(roll) + r * np.cos(roll)) / np.cos(pitch)  # Z-Y-X Euler kinematics
    integrated = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(imu.time))])
    logged = np.interp(imu.time, log.attitude.time, euler[:, 2])
    trend = np.polyfit(imu.time - imu.time[0], logged - integrated, 1)
    heading = integrated + np.polyval(trend, imu.time - imu.time[0])
    return np.interp(times, imu.time, heading)


@dataclass(frozen=True)
class FlightData:
    """One compass of one log, at its sample instants.

    Attributes
    ----------
    source : str
        ``FILE:COMPASS`` for messages and reports.
    time : (T,) array
        Magnetometer sample instants (s, the log's clock).
    raw : (T, 3) array
        Raw field, body FRD (T), before the autopilot's corrections.
    rotation : (T, 3, 3) array
        Body-to-NED rotation that carries the Earth field into the body frame (``R^T m_E``).
    euler : (T, 3) array
        The log's roll, pitch and yaw (rad) at ``time``: tilt compensation and the reference heading.
    motors, battery :
        The log's :class:`quadcosim.flightlogs.Motors` and :class:`quadcosim.flightlogs.Battery` (or None).
    log : FlightLog
        The log itself.
    compass : int
        The compass's index in the log.
    earth : (3,) array or None
        The Earth field model at the log's position (NED, T; :mod:`quadcosim.calibration.flight.earth`), or
        None: then it is fitted, free, per flight.
    """

    source: str
    time: np.ndarray
    raw: np.ndarray
    rotation: np.ndarray
    euler: np.ndarray
    motors: object
    battery: object
    log: object
    compass: int
    earth: np.ndarray | None = None

    def body(self, field: np.ndarray) -> np.ndarray:
        """``field`` (T, 3) in the raw field's frame turned into the body frame (the compass's rotation)."""
        return np.asarray(field) @ np.asarray(self.log.compasses[self.compass].rotation).T

    def autopilot_throttle(self, delay: float = 0.0) -> np.ndarray | None:
        """The autopilot's own throttle (T,) (``CTUN.ThO``, PX4's thrust) at ``time - delay`` (s),
        the signal its compass compensation multiplies; None when the log has none."""
        t = self.log.throttle if self.log is not None else None
        return None if t is None else np.interp(self.time - delay, t.time, t.value)

    def commands(self, delay: float = 0.0) -> np.ndarray:
        """Motor commands (T, N) (1) at ``time - delay`` (s)."""
        m = self.motors
        return np.column_stack([np.interp(self.time - delay, m.time, m.commands[:, n])
                                for n in range(m.commands.shape[1])])

    def throttle(self, delay: float = 0.0) -> np.ndarray:
        """Collective throttle (T,) (1), the mean command, at ``time - delay`` (s)."""
        return self.commands(delay).mean(axis=1)

    def current(self, delay: float = 0.0) -> np.ndarray | None:
        """Battery current (T,) (A) at ``time - delay`` (s); None without a current sensor."""
        b = self.battery
        return None if b is None or b.current is None else np.interp(self.time - delay, b.time, b.current)

    def voltage(self, delay: float = 0.0) -> np.ndarray:
        """Battery voltage (T,) (V) at ``time - delay`` (s); NaN when the log has no battery."""
        if self.battery is None:
            return np.full(len(self.time), np.nan)
        return np.interp(self.time - delay, self.battery.time, self.battery.voltage)

    def part(self, rows) -> FlightData:
        """The same flight restricted to ``rows`` (a boolean mask or indices of samples)."""
        return replace(self, time=self.time[rows], raw=self.raw[rows], rotation=self.rotation[rows],
                       euler=self.euler[rows])

    def split(self, test_fraction: float) -> tuple[FlightData, FlightData]:
        """(training, test): the test part is the last ``test_fraction`` (0..1) of the flight's time."""
        cut = self.time[0] + (1.0 - test_fraction) * (self.time[-1] - self.time[0])
        return self.part(self.time < cut), self.part(self.time >= cut)


def rate_refusal(log, compass: int) -> str | None:
    """Why compass ``compass`` of the :class:`quadcosim.flightlogs.FlightLog` ``log`` is logged too slowly for a
    flight calibration (its rate, the rate needed and the logging setting that gives it), or None."""
    from quadcosim.flightlogs.autopilots import of
    from quadcosim.flightlogs.model import rate

    chosen = log.compasses[compass] if 0 <= compass < len(log.compasses) else None
    if chosen is None:
        return None
    found = rate(chosen.time)
    if found >= MIN_COMPASS_RATE_HZ:
        return None
    faster = [f"{k}: {c.name} at {rate(c.time):.1f} Hz" for k, c in enumerate(log.compasses)
              if k != compass and rate(c.time) >= MIN_COMPASS_RATE_HZ]
    other = f"; this log has {', '.join(faster)} (--compass)" if faster else ""
    return (f"{log.path}: {chosen.name} is logged at {found:.1f} Hz; a flight calibration needs the compass at "
            f"{MIN_COMPASS_RATE_HZ:g} Hz or faster (below it the motors' field and its delay cannot be told apart): "
            f"{of(log.autopilot).faster_compass}{other}")


def fused(log, compass: int) -> bool:
    """Whether the log's heading fuses compass ``compass``: ArduPilot's ``COMPASS_PRIMARY``, PX4's first
    (:class:`quadcosim.flightlogs.autopilots.Autopilot`'s ``fused_compass``)."""
    from quadcosim.flightlogs.autopilots import of

    return compass == of(log.autopilot).fused_compass(log.params)


def flight_data(log, compass: int, attitude: str = "auto", earth=None, trim: bool = True) -> FlightData:
    """Align compass ``compass`` of the :class:`quadcosim.flightlogs.FlightLog` ``log`` for calibration.

    ``attitude`` chooses the rotation that removes the Earth field: ``"gyro"`` takes roll and pitch
    from the log and integrates the heading from the gyro (see :func:`gyro_heading`), so the heading
    does not come from the compass being calibrated; ``"log"`` takes the autopilot's attitude as it
    is; ``"auto"`` (default) is ``"gyro"`` for the compass the log's heading fuses and ``"log"`` for
    the others. The attitude is the board's (``AHRS_TRIM`` added back, unless ``trim`` is False),
    turned by the compass's own rotation into its raw field's frame (PX4). ``earth``: the Earth field
    model (NED, T) or None.

    Raises
    ------
    CalibrationError
        No such compass, no motors, attitude or IMU in the log (named), sensors that share no span
        of time, too few compass samples in the span they share, or an unknown ``attitude``.
    """
    from quadcosim.flightlogs import LogError

    if attitude not in ATTITUDES:
        raise CalibrationError(f"attitude {attitude!r} must be one of {', '.join(ATTITUDES)}")
    try:
        chosen = log.compass(compass)
        log.require("a flight calibration", "motors", "attitude", "imu")
        lo, hi = log.overlap((chosen.name, chosen), ("attitude", log.attitude), ("motors", log.motors),
                             ("battery", log.battery), (log.imus[0].name, log.imus[0]))
    except LogError as error:
        raise CalibrationError(str(error)) from None
    rows = (chosen.time >= lo) & (chosen.time <= hi)
    if rows.sum() < MIN_SAMPLES:
        raise CalibrationError(f"{log.path}: {chosen.name} has {rows.sum()} samples in the {hi - lo:.1f} s its "
                               f"sensors share ({lo:.1f} to {hi:.1f} s); a flight calibration needs at least "
                               f"{MIN_SAMPLES}: give a longer flight")
    time = chosen.time[rows]
    euler_log = euler_of(board_quaternions(log, trim))
    euler = np.column_stack([np.interp(time, log.attitude.time, euler_log[:, k]) for k in range(3)])
    used = euler.copy()
    if attitude == "gyro" or (attitude == "auto" and fused(log, compass)):
        used[:, 2] = gyro_heading(log, time, trim)
    rotation = rotation_of(used) @ np.asarray(chosen.rotation)
    return FlightData(f"{log.path}:{chosen.name}", time, chosen.raw[rows], rotation, euler, log.motors,
                      log.battery, log, compass, None if earth is None else np.asarray(earth, dtype=float))
