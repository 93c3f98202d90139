"""``metge``: dynamic calibration and compensation of the motor currents' field, Table 1 and Figure 3 of Metge et al.

Metge, Mégret, Giremus, Berthoumieu, Mazel, "Compensation dynamique des perturbations
magnétiques pour l'estimation d'attitude d'un micro-drone" (GRETSI 2013). The drone is
clamped, so the Earth field is constant in the sensor frame.

- Calibration set 1: motors off (``m0``), then each motor alone through a staircase of K
  command levels, 0 -> 1, motors in order 1..4; the settled part of each level is one of the
  K measurements (eq. 5). The sweep is made at two battery states (a full and a half-used
  battery): within one run the voltage barely moves, and the voltage terms of eq. 4 (J >= 1)
  need it to. After the first run, the free set: all four commands varied together, slowly,
  then fast, then slowly (as in flight).
- Calibration set 2: two other battery states, other noise seeds, another sweep order
  (motors 4..1, levels in a shuffled order).
- Each set gives a calibration (eqs. 6 to 8, orders I, J), and the rig record of the same set
  identifies the motor dynamics for the dynamics-aware compensation.
- Table 1: mean angular error between the compensated field (eq. 9) and the motors-off
  reference, rows "no dynamic calibration / calibration 1 / calibration 2", columns
  "set 1 / set 2 / free set"; Figure 3: the error against time on the free set, with the
  four commands.
- Regimes (option ``regime``): ``default``, the vehicle's own cables (each ESC's field along
  its own direction) and a free set swinging the commands by 0.13 about 0.5; ``paper``, the
  regime of the paper's free set: one common lead (every motor's field along one direction,
  up, as the current loops of a power board below the sensor make it), its gains scaled so
  that a one-motor sweep deflects the field as much as on the default vehicle (the sets keep
  their error), and a free set swinging 0.25. :mod:`quadcosim.studies.metge_free` measures what each
  ingredient does.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
from quadcosim.calibration import Calibration, Sweep, compensate, fit_dynamic, fit_motor_dynamics, order_study
from quadcosim.fmus import vehicle
from quadcosim.orchestrator import System, Table, portable
from quadcosim.orchestrator.parameters import apply
from quadcosim.scenarios import Option, Scenario
from quadcosim.scenarios.divergence import CLAMPED
from quadcosim.scenarios.figures import title_lines
from quadcosim.scenarios.plant import PLANT_BLOCKS, add_plant, angle_between, imu_parameters, save_figure

from quadcosim.infra.files import write_json
from quadcosim.infra.progress import status

PAPER_TABLE1 = {"none": {"set1": 11.142, "set2": 10.623, "free": 55.853},
                "calibration1": {"set1": 0.248, "set2": 0.635, "free": 7.970},
                "calibration2": {"set1": 0.483, "set2": 0.226, "free": 7.706}}

OPTIONS = {
    "levels": Option(12, "K: command levels per motor", minimum=2),
    "hold": Option(0.4, "time at each level (s)", minimum=0.02),
    "settle": Option(0.3, "start of each level left out of the K measurements (s): a free-wheeling "
                          "ESC lets the rotor coast down for a few tenths of a second", minimum=0.0),
    "reference": Option(1.0, "motors-off time at the start (s)", minimum=0.1),
    "rest": Option(0.5, "motors-off time after each motor (s)", minimum=0.0),
    "free": Option(12.0, "time of the free set: slow, fast, slow thirds (s)", minimum=0.0),
    "orders": Option("4,1", "I,J of eq. 4, or 'cv' for the orders chosen by cross-validation"),
    "soc1": Option("0.95,0.6", "battery states of charge of the runs of set 1 (1)"),
    "soc2": Option("0.8,0.45", "battery states of charge of the runs of set 2 (1)"),
    "mag_rate": Option(100.0, "magnetometer sample rate (Hz): the IMU runs at it on the clamped rig",
                       minimum=1.0),
    "seed1": Option(1, "noise and free-set seed of set 1"),
    "seed2": Option(2, "noise and sweep-order seed of set 2"),
    "noise": Option(True, "IMU white noise"),
    "dt": Option(1e-3, "macro step (s)", minimum=1e-5),
    "static": Option("", "static calibration file (JSON) for A, b_s; empty: the IMU's identity"),
    "regime": Option("default", "the vehicle's own ESC cables and a free set swinging 0.13, or 'paper': one common "
                                "lead (every motor's field up, -z_B) and a free set swinging 0.25, the regime of the "
                                "paper's free set", choices=("default", "paper")),
    "free_swing": Option("regime", "amplitude of each of the free set's three sines (1); regime: the regime's "
                                   "(0.13 default, 0.25 paper)", minimum=0.0, marker="regime"),
    "free_speed": Option(1.0, "the free set's frequencies times this (1)", minimum=0.01),
}
#: Swing (1) of each of the free set's three sines, by regime.
REGIME_SWING = {"default": 0.13, "paper": 0.25}
#: Direction (1, body frame) of the common lead's field in the ``paper`` regime: up, normal to a
#: power board below the magnetometer, whose current loops make a field normal to their plane.
COMMON_LEAD_DIRECTION = (0.0, 0.0, -1.0)
#: Command levels (1) of the one-motor sweep the common lead's gains are matched on: the
#: default rig's K = 12 levels.
MATCHED_LEVELS = tuple(np.arange(1, 13) / 12)
#: States of charge (1) of the battery of that sweep: those of the default sets' four runs.
MATCHED_SOCS = (0.95, 0.6, 0.8, 0.45)
RECORD = ["Setpoint.c", "MotorMagnetics.u_batt", "IMU.magneto"]
#: Block parameters the rig sets from its options (``--set`` on one of them is refused, naming the option).
DERIVED = {"IMU.noise_enabled": "noise", "IMU.seed": "seed1 and seed2", "IMU.sample_rate": "mag_rate",
           "IMU.mag_sample_rate": "mag_rate", "MotorMagnetics.soc0": "soc1 and soc2", "Quadrotor.clamped": "(the rig)"}
# a flight's IMU settings the clamped rig does not take: its biases are off and its rates its own
_NOT_ON_THE_RIG = ("IMU.bias_enabled", "IMU.b_g", "IMU.b_a", "IMU.gyro_bias", "IMU.acc_bias", "IMU.gyro_bias_walk",
                   "IMU.acc_bias_walk")


def block_settings(o: dict) -> dict:
    """The ``Block.parameter`` settings of options ``o`` (``--set MotorMagnetics.kappa1=8e-6``).

    Parameters
    ----------
    o : dict
        A scenario's options.

    Returns
    -------
    dict
        ``{"Block.parameter": value}``; every rig run of the scenario takes them.
    """
    return {k: v for k, v in o.items() if "." in k}


def vehicle_settings(o: dict) -> tuple[tuple[str, str], ...]:
    """The settings of a flight's options ``o`` that the clamped rig of the same vehicle takes:
    its motors, airframe and magnetometer, not the rig's own (:data:`DERIVED`) nor the IMU's
    biases; as sorted ``(name, text)`` pairs (hashable, for :func:`rig_calibration`'s cache).

    Parameters
    ----------
    o : dict
        A flight scenario's options (``tp``).

    Returns
    -------
    tuple of (str, str)
    """
    rig_blocks = ("MotorMagnetics.", "Quadrotor.", "IMU.")
    return tuple(sorted((k, str(v)) for k, v in block_settings(o).items()
                        if k.startswith(rig_blocks) and k not in DERIVED and not k.startswith(_NOT_ON_THE_RIG)))


def schedule(o: dict, set_number: int, sweeps: bool = True) -> tuple[list[tuple[str, float, float, int, float]], float]:
    """Phases ``(name, start, stop, motor, command)`` of a calibration set and its end time (s).

    Set 1: motors 1..4, levels rising; set 2: motors 4..1, levels shuffled (``set_number``);
    ``o``: the parsed options (levels, hold and settle times); ``sweeps`` False: the motors-off
    reference alone (a free set with no sweep before it)."""
    levels = np.arange(1, o["levels"] + 1) / o["levels"]
    motors = [0, 1, 2, 3] if sweeps else []
    if set_number == 2:
        motors = motors[::-1]
        levels = np.random.default_rng(o["seed2"]).permutation(levels)
    out, t = [("reference", 0.0, o["reference"], -1, 0.0)], o["reference"]
    for n in motors:
        for level in levels:
            out.append((f"motor{n + 1}", t, t + o["hold"], n, float(level)))
            t += o["hold"]
        t += o["rest"]
    return out, t


def free_swing(o: dict) -> float:
    """Amplitude (1) of each of the free set's three sines: option ``free_swing``, or the regime's."""
    return REGIME_SWING[o["regime"]] if o["free_swing"] == "regime" else o["free_swing"]


def free_commands(o: dict, t: np.ndarray) -> np.ndarray:
    """All four commands together: sums of three sinusoids of amplitude :func:`free_swing` each
    about 0.5, slow (0.1 to 0.6 Hz) in the outer thirds, fast (1 to 4 Hz) in the middle third,
    every frequency times ``free_speed``; clipped to [0, 1]. ``o``: the options (``seed1``
    draws the frequencies and phases); ``t``: times from the start of the free set (s)."""
    rng = np.random.default_rng(o["seed1"] + 100)
    third, swing, speed = o["free"] / 3, free_swing(o), o["free_speed"]
    fast = (t >= third) & (t < 2 * third)
    c = np.empty((len(t), 4))
    for n in range(4):
        slow_f, fast_f = speed * rng.uniform(0.1, 0.6, 3), speed * rng.uniform(1.0, 4.0, 3)
        phase = rng.uniform(0, 2 * np.pi, (2, 3))
        slow = portable.sin(2 * np.pi * slow_f[:, None] * t + phase[0][:, None]).sum(axis=0)
        quick = portable.sin(2 * np.pi * fast_f[:, None] * t + phase[1][:, None]).sum(axis=0)
        c[:, n] = np.where(fast, 0.5 + swing * quick, 0.5 + swing * slow)
    return np.clip(c, 0.0, 1.0)


def steady_supply_current(c, u) -> np.ndarray:
    """Steady supply current ``c i`` (A) of one default motor at commands ``c`` (1) and battery
    voltage ``u`` (V): ``c u = R i + k_e omega`` with ``k_e i = k_m omega^2`` (the plant's
    steady state, :func:`quadcosim.fmus.vehicle.steady_command` solved for ``omega``)."""
    c, u = np.asarray(c, dtype=float), np.asarray(u, dtype=float)
    a = vehicle.MOTOR_RESISTANCE * vehicle.DRAG_TORQUE_COEFF / vehicle.MOTOR_KE  # V s^2
    omega = (-vehicle.MOTOR_KE + np.sqrt(vehicle.MOTOR_KE**2 + 4 * a * c * u)) / (2 * a)
    return c * vehicle.steady_current(omega)


def one_motor_deflection_deg(directions, gains) -> float:
    """Mean angle (deg) by which one motor alone, swept over :data:`MATCHED_LEVELS` at steady
    state, turns the Earth field at the clamped rig, over the four motors and the battery
    states :data:`MATCHED_SOCS` (open-circuit voltage); ``directions`` (4, 3) and ``gains``
    (4,) (T/A) of the cables' fields. A static prediction of Table 1's uncompensated sets."""
    m0 = np.array(vehicle.EARTH_FIELD)  # the rig is level, heading north: {B} = {I}
    v = np.asarray(directions, dtype=float)
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    u = vehicle.BATTERY_CELLS * np.array([vehicle.cell_voltage(soc) for soc in MATCHED_SOCS])
    current = steady_supply_current(np.array(MATCHED_LEVELS)[None, :], u[:, None]).ravel()  # A, (socs x levels)
    fields = m0 + np.asarray(gains, dtype=float)[:, None, None] * current[None, :, None] * v[:, None, :]
    return float(np.degrees(angle_between(fields.reshape(-1, 3), m0)).mean())


def common_lead_settings(direction=COMMON_LEAD_DIRECTION) -> dict:
    """``MotorMagnetics`` settings of one common lead: every motor's field along ``direction``
    (1, body frame), the default gains times the one factor that keeps the one-motor sweep's
    deflection (:func:`one_motor_deflection_deg`) that of the default vehicle.

    Parameters
    ----------
    direction : sequence of 3 float
        Direction of the common field in {B} (normalised here).

    Returns
    -------
    dict
        ``{"MotorMagnetics.kappaN": T/A, "MotorMagnetics.vN_a": 1}``.
    """
    from scipy.optimize import brentq

    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    gains = np.array(vehicle.MOTOR_FIELD_GAIN)
    target = one_motor_deflection_deg(vehicle.MOTOR_FIELD_DIRECTION, gains)
    v = np.tile(d, (4, 1))
    scale = brentq(lambda s: one_motor_deflection_deg(v, s * gains) - target, 1e-3, 1e3, xtol=1e-12)
    out = {f"MotorMagnetics.kappa{n + 1}": float(scale * g) for n, g in enumerate(gains)}
    return out | {f"MotorMagnetics.v{n + 1}_{a}": float(d[k]) for n in range(4) for k, a in enumerate("xyz")}


def cable_directions(o: dict) -> np.ndarray:
    """Unit directions (4, 3) of the cables' fields of the options' vehicle: the regime's, or
    those set (``MotorMagnetics.vN_a``), else the default vehicle's."""
    settings = regime_settings(o) | block_settings(o)
    v = np.array([[float(settings.get(f"MotorMagnetics.v{n + 1}_{a}", vehicle.MOTOR_FIELD_DIRECTION[n][k]))
                   for k, a in enumerate("xyz")] for n in range(4)])
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def regime_settings(o: dict) -> dict:
    """The ``MotorMagnetics`` settings of the options' regime: none for ``default``,
    :func:`common_lead_settings` for ``paper``."""
    return common_lead_settings() if o["regime"] == "paper" else {}


def socs(o: dict, set_number: int) -> list[float]:
    """Battery states of charge (1) of the runs of set ``set_number``, from its option."""
    text = o[f"soc{set_number}"]
    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        raise ValueError(f"option soc{set_number} = {text!r} must be comma-separated states of charge") from None
    if not values or not all(0.0 <= v <= 1.0 for v in values):
        raise ValueError(f"option soc{set_number} = {text!r}: each state of charge must be within [0, 1]")
    return values


def commands(o: dict, set_number: int, free: bool = False, sweeps: bool = True) -> tuple[np.ndarray, float, float]:
    """Command table (rows every macro step, columns motors 1..4), the end of the sweeps and the end
    of the run (s), of calibration set ``set_number``, followed by the free set when ``free``;
    without the sweeps when not ``sweeps``."""
    phases, end = schedule(o, set_number, sweeps)
    stop = end + (o["free"] if free else 0.0)
    t = np.arange(int(round(stop / o["dt"])) + 1) * o["dt"]
    c = np.zeros((len(t), 4))
    for _, a, b, motor, level in phases[1:]:
        c[(t >= a - 1e-9) & (t < b - 1e-9), motor] = level
    if free and o["free"] > 0:
        inside = t >= end - 1e-9
        c[inside] = free_commands(o, t[inside] - end)
    return c, end, stop


def system_for(o: dict, set_number: int, run: int, sweeps: bool = True) -> System:
    """Run ``run`` of calibration set ``set_number``; the first run of set 1 ends with the free set
    (which is all it holds, after the motors-off reference, when not ``sweeps``)."""
    c, _, _ = commands(o, set_number, free=(set_number, run) == (1, 0), sweeps=sweeps)
    system = System(dt=o["dt"])
    system.add(Table("Setpoint", ["c1", "c2", "c3", "c4"], c, units=dict.fromkeys(("c1", "c2", "c3", "c4"), "1")))
    seed = o[f"seed{set_number}"] + 10 * run
    add_plant(system, quadrotor={"clamped": True}, motors={"soc0": socs(o, set_number)[run]},
              imu=imu_parameters(o["noise"], False, seed, sample_rate=o["mag_rate"],
                                 mag_sample_rate=o["mag_rate"]))
    system.connect("Setpoint.c", "MotorMagnetics.c")
    settings = regime_settings(o) | block_settings(o)
    if settings:  # every run of the rig is the same vehicle: the parameters set reach them all
        apply(system, settings, DERIVED)
    return system


def build(o: dict) -> System:
    """The first run of set 1 (full battery, then the free set), after checking the options."""
    if not 0 <= o["settle"] < o["hold"]:
        raise ValueError(f"settle = {o['settle']} s must be shorter than hold = {o['hold']} s")
    socs(o, 1), socs(o, 2)
    parse_orders(o["orders"])
    load_static(o)  # read before the simulation: a file refused after it would waste the run
    if abs(round(1.0 / (o["mag_rate"] * o["dt"])) * o["mag_rate"] * o["dt"] - 1.0) > 1e-9:
        raise ValueError(f"mag_rate = {o['mag_rate']} Hz must divide the macro step rate {1 / o['dt']:g} Hz")
    clash = sorted(set(regime_settings(o)) & set(block_settings(o)))
    if clash:
        raise ValueError(f"regime={o['regime']} sets {', '.join(clash)} (one common lead): leave them out, or "
                         "choose regime=default to set the cables yourself")
    return system_for(o, 1, 0)


def parse_orders(text: str):
    """``(I, J)`` from ``text`` ``"I,J"``, or ``None`` for ``"cv"`` (chosen by cross-validation)."""
    if text == "cv":
        return None
    try:
        I, J = (int(x) for x in text.split(","))
    except ValueError:
        raise ValueError(f"option orders = {text!r} must be 'I,J' (for instance 4,1) or 'cv'") from None
    if I < 1 or J < 0:
        raise ValueError(f"option orders = {text!r}: I must be >= 1 and J >= 0")
    return I, J


class RigRun:
    """One recorded run on the clamped rig: arrays, phases, and the rows of its K measurements,
    from the run's ``result``, its options ``o`` and its calibration set ``set_number``
    (``sweeps`` False: a free set alone, after the motors-off reference)."""

    def __init__(self, result, o: dict, set_number: int, sweeps: bool = True):
        self.time = result.time
        self.field = result["IMU.magneto"]
        self.commands = result["Setpoint.c"]
        self.voltage = result["MotorMagnetics.u_batt"]
        self.phases, self.end = schedule(o, set_number, sweeps)
        t = self.time
        _, a, b, _, _ = self.phases[0]
        self.reference = self.field[(t >= a + 0.1) & (t < b)].mean(axis=0)  # m0, after the start-up
        self.motor_of = np.full(len(t), -1)
        for _, a, b, motor, _ in self.phases[1:]:
            self.motor_of[(t >= a + o["settle"]) & (t < b - 1e-9)] = motor
        self.settled = self.motor_of >= 0
        self.sweeping = (t >= self.phases[1][1]) & (t < self.end) if len(self.phases) > 1 else np.zeros(len(t), bool)
        self.free = t >= self.end

    def record(self):
        """``(time (s), magneto (T), commands (1), voltage (V))`` up to the end of the sweeps."""
        rows = self.time < self.end
        return self.time[rows], self.field[rows], self.commands[rows], self.voltage[rows]


class RigSet:
    """A calibration set: runs at several battery states, pooled (each run's readings are taken
    relative to its own motors-off reference)."""

    def __init__(self, runs: list[RigRun]):
        self.runs = runs
        self.reference = np.mean([r.reference for r in runs], axis=0)

    def sweeps(self) -> list[Sweep]:
        """Each motor's K measurements over all runs, against the set's mean ``m0``."""
        out = []
        for n in range(4):
            parts = [(r.field[r.motor_of == n] - r.reference + self.reference, r.commands[r.motor_of == n, n],
                      r.voltage[r.motor_of == n]) for r in self.runs]
            out.append(Sweep(*(np.concatenate(x) for x in zip(*parts, strict=True))))
        return out


def load_static(o):
    """The static calibration of option ``static`` (a calibration file), or ``None``."""
    return Calibration.load(o["static"]).static if o["static"] else None


def calibrate(rig: RigSet, orders, static, sample_rate: float, name: str) -> Calibration:
    """Eqs. 5 to 8 on the K measurements of the set ``rig`` and the motor dynamics on its records.

    ``orders``: ``(I, J)``; ``static``: the static (hard and soft iron) calibration;
    ``sample_rate`` (Hz): the magnetometer's; ``name``: recorded in the file as its maker.
    """
    model = fit_dynamic(rig.reference, rig.sweeps(), orders)
    dynamics = fit_motor_dynamics([r.record() for r in rig.runs], [r.reference for r in rig.runs], model.v,
                                  sample_rate, progress=status)
    return Calibration(4, static, model, dynamics, rig.reference, {"made_by": f"quadcosim run metge ({name})"})


def errors_deg(cal: Calibration, run: RigRun, mode: str, sample_rate: float) -> np.ndarray:
    """Angular error (deg) of the field compensated by ``cal`` in ``mode`` (refreshed at
    ``sample_rate``, Hz) against the statically corrected motors-off reference of the run, at
    every row."""
    out = compensate(cal, run.time, run.field, run.commands, run.voltage, mode, sample_rate)
    m0 = run.reference if cal.static is None else cal.static.correct(run.reference)
    return np.degrees(angle_between(out, m0))


def set_error(cal, rig: RigSet, mode, rate, rows: str) -> float:
    """Mean error (deg) over the chosen rows (``settled`` or ``sweeping``) of every run of the set
    ``rig``, compensated by ``cal`` in ``mode`` at ``rate`` (Hz)."""
    return float(np.concatenate([errors_deg(cal, r, mode, rate)[getattr(r, rows)] for r in rig.runs]).mean())


def record_sets(result, o: dict, out) -> dict[int, list[RigRun]]:
    """The runs of both calibration sets: the scenario's own run (set 1, first battery state, with
    the free set, ``result``) and the others, each saved under ``out/set<k>_run<i>``."""
    runs = {1: [RigRun(result, o, 1)], 2: []}
    for set_number in (1, 2):
        for run in range(len(runs[set_number]), len(socs(o, set_number))):
            status(f"metge: rig run {run + 1} of set {set_number} ({commands(o, set_number)[2]:.0f} s simulated)")
            recorded = system_for(o, set_number, run).run(commands(o, set_number)[2], record=RECORD)
            if out is not None:
                recorded.save(out / f"set{set_number}_run{run}")
            runs[set_number].append(RigRun(recorded, o, set_number))
    return runs


def table1(cals: dict, rig1: RigSet, rig2: RigSet, rate: float) -> dict:
    """Table 1 (deg): rows ``none`` (static calibration only) and each calibration (eq. 9),
    columns the settled rows of set 1 and set 2 and the free set; the same sets with every row
    (step transients included); the dynamics-aware free-set errors; and the error series of the
    first run of set 1 (for Figure 3). ``cals``: the calibrations by name; ``rig1``, ``rig2``: the
    two sets; ``rate`` (Hz): the magnetometer's."""
    first = rig1.runs[0]
    table, whole, dynamic_free, series = {}, {}, {}, {}
    for row, cal in cals.items():
        mode = "static" if row == "none" else "metge"
        series[row] = errors_deg(cal, first, mode, rate)
        table[row] = {"set1": set_error(cal, rig1, mode, rate, "settled"),
                      "set2": set_error(cal, rig2, mode, rate, "settled"),
                      "free": float(series[row][first.free].mean())}
        whole[row] = {"set1": set_error(cal, rig1, mode, rate, "sweeping"),
                      "set2": set_error(cal, rig2, mode, rate, "sweeping")}
        if row != "none":
            series[row + "_dynamic"] = errors_deg(cal, first, "dynamic", rate)
            dynamic_free[row] = float(series[row + "_dynamic"][first.free].mean())
    return {"table": table, "whole": whole, "dynamic_free": dynamic_free, "series": series}


PAPER = ("Metge et al., \"Compensation dynamique des perturbations magnétiques pour l'estimation "
         "d'attitude d'un micro-drone\", 2013")


def run_line(o: dict) -> str:
    """The calibration runs in words, for the figures' titles.

    Parameters
    ----------
    o : dict
        The scenario's options.

    Returns
    -------
    str
    """
    regime = "" if o["regime"] == "default" else f"regime {o['regime']} (one common lead), "
    speed = "" if o["free_speed"] == 1.0 else f" x{o['free_speed']:g} in frequency"
    return (f"{regime}K = {o['levels']} command levels of {o['hold']:g} s per motor, free set {o['free']:g} s "
            f"(swing {free_swing(o):g}{speed}), magnetometer {o['mag_rate']:g} Hz, IMU noise "
            f"{'on' if o['noise'] else 'off'}, battery states {o['soc1']} (set 1) and {o['soc2']} (set 2)")


def figure3(first: RigRun, numbers: dict, o: dict, out):
    """The paper's Figure 3: angular error against time on the free set, before and after
    compensation, above the four commands. ``first``: the first run of set 1; ``numbers``: as
    :func:`table1` returns; ``out``: the folder of the figure (None: no file)."""
    import matplotlib.pyplot as plt

    rows, series, table = first.free, numbers["series"], numbers["table"]
    t = first.time[rows] - first.end
    third = o["free"] / 3
    fig, axes = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True)
    axes[0].plot(t, series["none"][rows], lw=0.8, label=f"no dynamic calibration (mean {table['none']['free']:.1f}°)")
    axes[0].plot(t, series["calibration1"][rows], lw=0.8,
                 label=f"eq. 9, calibration 1 (mean {table['calibration1']['free']:.2f}°)")
    axes[0].plot(t, series["calibration1_dynamic"][rows], lw=0.8,
                 label=f"motor dynamics, calibration 1 (mean {numbers['dynamic_free']['calibration1']:.2f}°)")
    axes[0].set_ylabel("angular error (deg)")
    axes[0].set_yscale("log")
    axes[0].legend(fontsize=8)
    axes[0].grid(True, alpha=0.3, which="both")
    fig.suptitle(title_lines("metge: free set, drone clamped: angular error of the measured field before and after "
                             "compensation, as in Fig. 3 of " + PAPER, run_line(o)), fontsize=9)
    for n in range(4):
        axes[1].plot(t, first.commands[rows, n], lw=0.8, label=f"c{n + 1}")
    axes[1].set_ylabel("ESC command (1)")
    axes[1].set_xlabel("time in the free set (s); shaded: fast command changes")
    axes[1].legend(fontsize=8, ncol=4)
    for ax in axes:
        ax.axvspan(third, 2 * third, alpha=0.08, color="k")
    return save_figure(fig, out, "figure3_free_set.png")


def table1_text(numbers: dict, orders, o: dict, out):
    """Table 1 as a Markdown table (``table1.md``), each cell beside the paper's value;
    ``numbers`` as :func:`table1` returns, ``orders`` the model's ``(I, J)``, ``o`` the scenario's
    options (named in the heading), ``out`` the folder of the file (None: no file). Returns the
    file name written, or None."""
    if out is None:
        return None
    from quadcosim.infra.files import atomic_path

    table, dynamic = numbers["table"], numbers["dynamic_free"]
    names = {"none": "no dynamic calibration", "calibration1": "calibration 1", "calibration2": "calibration 2"}
    lines = [f"Mean angular error (deg) of the measured field, simulated (the paper's value), Table 1 of {PAPER}.",
             f"Orders I = {orders[0]}, J = {orders[1]}; {run_line(o)}.", "",
             "| | set 1 | set 2 | free set |", "|---|---|---|---|"]
    for row, name in names.items():
        cells = [f"{table[row][c]:.3f} ({PAPER_TABLE1[row][c]:.3f})" for c in ("set1", "set2", "free")]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    lines.append(f"| motor dynamics (cal. 1 / 2) | | | {dynamic['calibration1']:.3f} / "
                 f"{dynamic['calibration2']:.3f} |")
    with atomic_path(out / "table1.md") as temporary:
        Path(temporary).write_text("\n".join(lines) + "\n")
    return "table1.md"


def fast_third(run: RigRun, o: dict) -> np.ndarray:
    """Which rows of the free set of ``run`` fall in its middle, fast third (options ``o``).

    Parameters
    ----------
    run : RigRun
        The run holding the free set (the first of set 1).
    o : dict
        The scenario's options (``free``, s).

    Returns
    -------
    numpy.ndarray of bool
        One per row of the free set.
    """
    t_free = run.time[run.free] - run.end
    return (t_free >= o["free"] / 3) & (t_free < 2 * o["free"] / 3)


def report(result, o, out) -> dict:
    """Record set 2 and the second battery state, calibrate on each set, and return Table 1,
    the dynamics-aware free-set error, the order study and the identified motor dynamics;
    writes ``calibration1.json``, ``calibration2.json`` and the two figures into ``out``.
    ``result``: the scenario's own run; ``o``: the parsed options."""
    orders, rate = parse_orders(o["orders"]), o["mag_rate"]
    static = load_static(o)
    runs = record_sets(result, o, out)
    rig1, rig2 = RigSet(runs[1]), RigSet(runs[2])
    status("metge: cross-validating the orders (I, J) between the sets")
    study = order_study([(rig1.reference, rig1.sweeps()), (rig2.reference, rig2.sweeps())])
    orders = orders or study["best"]
    status("metge: calibrating on each set (eqs. 5 to 8, then the motors' dynamics)")
    cals = {"calibration1": calibrate(rig1, orders, static, rate, "set 1"),
            "calibration2": calibrate(rig2, orders, static, rate, "set 2")}
    if out is not None:
        for name, cal in cals.items():
            write_json(out / f"{name}.json", cal.to_dict())  # atomically
    status("metge: Table 1 (every run compensated by each calibration)")
    numbers = table1({"none": Calibration(4, static), **cals}, rig1, rig2, rate)
    table, dynamic_free, first = numbers["table"], numbers["dynamic_free"], rig1.runs[0]
    fast = fast_third(first, o)
    e_free = numbers["series"]["calibration1"][first.free]
    ed_free = numbers["series"]["calibration1_dynamic"][first.free]
    true_v = cable_directions(o)
    figures = [figure3(first, numbers, o, out), table1_text(numbers, orders, o, out)]
    return {
        "table1_deg": table,
        "free_set_dynamic_deg": dynamic_free["calibration1"],
        "free_set_dynamic_calibration2_deg": dynamic_free["calibration2"],
        "paper_table1_deg": PAPER_TABLE1,
        "improvement_factor_sets": {f"{r}_{c}": table["none"][c] / table[r][c]
                                    for r in ("calibration1", "calibration2") for c in ("set1", "set2")},
        "dynamic_gain_free": table["calibration1"]["free"] / dynamic_free["calibration1"],
        **_ranges(table, study["scores"]),
        "sets_with_transients_deg": numbers["whole"],
        "free_eq9_slow_fast_deg": {"slow": float(e_free[~fast].mean()), "fast": float(e_free[fast].mean())},
        "free_dynamic_slow_fast_deg": {"slow": float(ed_free[~fast].mean()), "fast": float(ed_free[fast].mean())},
        "direction_error_deg": {name: np.degrees(np.arccos(np.clip((c.field.v * true_v).sum(axis=1), -1, 1))).tolist()
                                for name, c in cals.items()},
        "regime": o["regime"],
        "free_swing": free_swing(o),
        "orders": list(orders),
        "order_study_uT": {f"I={i},J={j}": s * 1e6 for (i, j), s in study["scores"].items()},
        "order_study_best": list(study["best"]),
        "magnetometer_rate_hz": rate,
        "battery_voltage_v": {f"set{k}_run{i}": float(r.voltage[r.sweeping].mean())
                              for k in (1, 2) for i, r in enumerate(runs[k])},
        "motor_dynamics": {name: c.to_dict()["dynamics"] for name, c in cals.items()},
        "figures": [f for f in figures if f],
    }


def _ranges(table: dict, scores: dict) -> dict:
    """The figures the findings quote from Table 1 and the order study: the range over both
    calibrations and both sets after eq. 9 (deg), of the improvement on the sets (1), and the
    order study's scores of (3, 1) and of the best (I, 0) over that of (4, 1) (1)."""
    after = [table[r][c] for r in ("calibration1", "calibration2") for c in ("set1", "set2")]
    gains = [table["none"][c] / table[r][c] for r in ("calibration1", "calibration2") for c in ("set1", "set2")]
    reference = scores.get((4, 1))
    ratios = {}
    if reference:
        ratios = {"order_study_3_1_over_4_1": scores[(3, 1)] / reference if (3, 1) in scores else None,
                  "order_study_best_j0_over_4_1": min(v for (_, j), v in scores.items() if j == 0) / reference}
    return {"sets_calibrated_range_deg": [min(after), max(after)], "improvement_range": [min(gains), max(gains)],
            **ratios}


def duration(o: dict) -> float:
    """Length (s) of the scenario's own run: set 1's sweeps and the free set."""
    return commands(o, 1, free=True)[2]


SCENARIO = Scenario("metge", __doc__.split(": ", 1)[1].splitlines()[0], OPTIONS, build, report,
                    duration=duration, extra={"record": RECORD, "derived": DERIVED, "divergence": CLAMPED,
                                              "blocks": {"Setpoint": Table, **PLANT_BLOCKS}})


# --- the rig calibration a closed loop's compensation uses (quadcosim.scenarios.compensation) -----


@functools.lru_cache(maxsize=4)
def rig_calibration(orders: str = "4,1", levels: int = 8, settings: tuple = ()) -> Calibration:
    """Calibration 1 of this scenario with ``levels`` command levels, made on the clamped rig
    (about 30 s of simulated rig time); cached for the process. The tp vehicle has no soft or
    hard iron, so the static part is the identity.

    Parameters
    ----------
    orders : str
        ``"I,J"`` of eq. 4.
    levels : int
        Command levels per motor.
    settings : tuple of (str, str)
        Block parameters of the vehicle (:func:`vehicle_settings`), set on every rig run.
    """
    o = SCENARIO.parse({"orders": orders, "levels": levels} | dict(settings))
    runs, count = [], len(socs(o, 1))
    for run in range(count):
        status(f"calibrating the motor-current field on the clamped rig: run {run + 1} of {count} "
               f"({commands(o, 1)[2]:.0f} s simulated)")
        recorded = system_for(o, 1, run).run(commands(o, 1)[2], record=RECORD)
        runs.append(RigRun(recorded, o, 1))
    status("identifying the field model (eqs. 5 to 8) and the motors' dynamics")
    return calibrate(RigSet(runs), parse_orders(orders), None, o["mag_rate"], "set 1, made for tp")
