"""Benchmark of the co-simulation master against C reference loops (``quadcosim bench``).

Measures, in one run, per macro step at 1 kHz, CPU time of the stepping loop only
(instantiation excluded), in the same process:

- the open loop: the orchestrator on the ``open-loop`` scenario (three FMUs, scripted commands,
  every output recorded at every step), and ``open_loop`` of ``benchmarks/c/loops.c``: the
  same FMI calls on FMUs with the same parameters, the same command table, the same recording
  and non-finite check, written by hand in C;
- the closed loop: the orchestrator on ``tp`` with the explicit filter (IMU noise and bias on,
  controller fed by the ground truth), and ``closed_loop`` of ``loops.c``: the same FMI calls,
  the explicit filter and the controller written in C, the same recording;
- in each repeat the orchestrator and the C loop are timed back to back and their ratio kept;
  the figures are the median ratio over ``repeats`` and its spread (lowest, highest). The
  trajectories are compared bit for bit: every recorded signal of the C loop must equal the
  orchestrator's (``*_identical``).

The keys of :func:`quadcosim.benchmarks.estimators.measure` (the batch path) and of
:func:`quadcosim.benchmarks.save.figures` (``save_fraction``) join the same JSON object.
"""

from __future__ import annotations

import ctypes
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from quadcosim.benchmarks import estimators, fmu_steps, reference_library
from quadcosim.benchmarks.save import figures as save_figures

CLOSED_LOOP = {"estimator": "explicit", "noise": True, "bias": True}  # tp options of the closed loop

_double, _pointer, _size = ctypes.c_double, ctypes.c_void_p, ctypes.c_size_t


class _Fmu(ctypes.Structure):
    _fields_ = [("set", _pointer), ("get", _pointer), ("step", _pointer), ("component", _pointer)]


class _Refs(ctypes.Structure):
    _fields_ = [("vr", _pointer), ("n", _size)]


_CONTROL_NAMES = ("mass", "jx", "jy", "jz", "gravity", "thrust_coeff", "max_rotor_thrust", "resistance", "ke",
                  "drag_torque_coeff", "max_tilt", "kp", "kd", "kp_yaw", "kd_yaw", "kp_z", "kd_z", "kp_xy",
                  "kd_xy", "ki_xy")


class _Control(ctypes.Structure):
    _fields_ = [(name, _double) for name in _CONTROL_NAMES] + [("mixer_inverse", _double * 16)]


class _Explicit(ctypes.Structure):
    _fields_ = [("k1", _double), ("k2", _double), ("kP", _double), ("kI", _double), ("gravity", _double * 3),
                ("field", _double * 3), ("q0", _double * 4), ("b0", _double * 3)]


_REFS = ("motors_in", "motors_out", "body_rotors", "body_wind", "body_out", "imu_rotors", "imu_field", "imu_motion",
         "imu_out")


class _Loop(ctypes.Structure):
    _fields_ = ([("motors", _Fmu), ("body", _Fmu), ("imu", _Fmu)] + [(name, _Refs) for name in _REFS]
                + [("setpoint", _pointer), ("setpoint_width", ctypes.c_long), ("wind", _pointer), ("field", _pointer),
                   ("steps", ctypes.c_long), ("dt", _double), ("record", _pointer), ("width", ctypes.c_long),
                   ("control", _pointer), ("filter", _pointer), ("failed_step", ctypes.c_long),
                   ("failed_call", ctypes.c_int)])


def _address(function) -> int:
    return ctypes.cast(function, _pointer).value


class ReferenceLoop:
    """The C loop of ``benchmarks/c/loops.c`` on fresh FMU instances of a built ``system``.

    Parameters
    ----------
    system : quadcosim.orchestrator.System
        The ``open-loop`` or ``tp`` system, whose blocks give the FMU parameters, the setpoint
        table, the constant inputs, and the filter's and controller's settings.
    seconds : float
        Simulated time (s).
    """

    def __init__(self, system, seconds: float):
        from quadcosim.orchestrator.fmu import FMUInstance

        blocks = system.blocks
        self.closed = "Controller" in blocks
        if self.closed:  # refused here, before any FMU is instantiated
            self.control, self.filter = _control(blocks["Controller"]), _explicit(blocks["Quaternion_estim"])
        self.steps, self.dt = int(round(seconds / system.dt)), system.dt
        self.keep = []  # arrays the C loop points into
        self.fmus = {name: FMUInstance(blocks[name].model, blocks[name].parameters, name=name)
                     for name in ("MotorMagnetics", "Quadrotor", "IMU")}
        setpoint = blocks["Setpoint"]
        setpoint.start(0.0, system.dt)
        rows = [setpoint.segment(k)[1] for k in range(0, self.steps + 1, setpoint.chunk)]
        table = self._kept(np.concatenate(rows)[:self.steps + 1])
        self.names = [f"{name}.{y}" for name in ("Setpoint", "MotorMagnetics", "Quadrotor", "IMU")
                      + (("Quaternion_estim", "Controller") if self.closed else ()) for y in blocks[name].outputs]
        self.record = np.empty((self.steps + 1, len(self.names)))
        wind = self._kept([blocks[f"Const_Quadrotor_wind_{axis}"].values[0] for axis in "xyz"])
        field = self._kept(blocks["Const_IMU_b_d"].values if "Const_IMU_b_d" in blocks else np.zeros(3))
        self.loop = _Loop(**self._fmu_fields(blocks), setpoint=table.ctypes.data, setpoint_width=table.shape[1],
                          wind=wind.ctypes.data, field=field.ctypes.data, steps=self.steps, dt=self.dt,
                          record=self.record.ctypes.data, width=len(self.names))
        if self.closed:
            self.loop.control, self.loop.filter = ctypes.addressof(self.control), ctypes.addressof(self.filter)

    def _kept(self, values) -> np.ndarray:
        array = np.ascontiguousarray(values, dtype=float)
        self.keep.append(array)
        return array

    def _refs(self, fmu, names) -> _Refs:
        vr = self.fmus[fmu].vr(list(names))
        self.keep.append(vr)
        return _Refs(vr.ctypes.data, len(vr))

    def _fmu_fields(self, blocks) -> dict:
        fields = {key: _Fmu(_address(f.raw_set_real), _address(f.raw_get_real), _address(f.raw_do_step), f.component)
                  for key, f in zip(("motors", "body", "imu"), self.fmus.values(), strict=True)}
        rotors = [f"omega_r{n}" for n in range(1, 5)]
        return fields | {
            "motors_in": self._refs("MotorMagnetics", [f"c{n}" for n in range(1, 5)]),
            "motors_out": self._refs("MotorMagnetics", blocks["MotorMagnetics"].outputs),
            "body_rotors": self._refs("Quadrotor", rotors + [f"domega_r{n}" for n in range(1, 5)]),
            "body_wind": self._refs("Quadrotor", ["wind_x", "wind_y", "wind_z"]),
            "body_out": self._refs("Quadrotor", blocks["Quadrotor"].outputs),
            "imu_rotors": self._refs("IMU", rotors),
            "imu_field": self._refs("IMU", ["b_d_x", "b_d_y", "b_d_z"]),
            "imu_motion": self._refs("IMU", ["q0", "q1", "q2", "q3", "omega_x", "omega_y", "omega_z", "f_x", "f_y",
                                             "f_z"]),
            "imu_out": self._refs("IMU", blocks["IMU"].outputs),
        }

    def run(self) -> float:
        """Run the loop once; its CPU time (s).

        Raises
        ------
        RuntimeError
            An FMI call failed or a value became non-finite (the step is named).
        """
        function = getattr(reference_library("loops"), "closed_loop" if self.closed else "open_loop")
        function.restype = ctypes.c_int
        started = time.thread_time()
        status = function(ctypes.byref(self.loop))
        seconds = time.thread_time() - started
        if status:
            raise RuntimeError(f"the C reference loop failed at step {self.loop.failed_step} (status {status})")
        return seconds

    def close(self):
        """Free the FMU instances."""
        for fmu in self.fmus.values():
            fmu.close()


def _control(block) -> _Control:
    from quadcosim.flight.controller import PARAMETERS

    values = dict(zip(PARAMETERS, block.parameters, strict=True))
    return _Control(*[values[name] for name in _CONTROL_NAMES], (_double * 16)(*block.mixer_inverse.ravel()))


def _explicit(block) -> _Explicit:
    from quadcosim.estimators import layout

    gains, config, vector = block.gains, block.config, _double * 3
    if block.kind != "explicit" or any(gains[name] for name in gains if name not in ("k1", "k2", "kP", "kI")):
        raise ValueError("the C reference is the explicit filter without corrections")
    return _Explicit(gains["k1"], gains["k2"], gains["kP"], gains["kI"],
                     vector(*config[layout.GRAVITY:layout.GRAVITY + 3]),
                     vector(*config[layout.FIELD:layout.FIELD + 3]), (_double * 4)(*block.q0), vector(*block.b0))


def compare(scenario: str, settings: dict, seconds: float, repeats: int) -> dict:
    """The orchestrator against its C reference loop on one scenario, ``repeats`` times.

    Parameters
    ----------
    scenario : str
        ``"open-loop"`` or ``"tp"``.
    settings : dict
        Scenario options.
    seconds : float
        Simulated time per run (s).
    repeats : int
        Runs of each, back to back.

    Returns
    -------
    dict
        ``ratios`` (orchestrator over C, CPU time, one per repeat), ``us_per_step`` and
        ``c_us_per_step`` (the lowest over the repeats, µs), ``identical`` (every recorded signal
        of the C loop equal, bit for bit, to the orchestrator's, in every repeat).
    """
    from quadcosim import scenarios

    definition = scenarios.get(scenario)
    options = definition.parse({"duration": seconds} | settings)
    ratios, ours, theirs, identical = [], [], [], True
    for _ in range(repeats):
        result = definition.build(options).run(seconds)
        reference = ReferenceLoop(definition.build(options), seconds)
        try:
            c_seconds = reference.run()
        finally:
            reference.close()
        steps = reference.steps
        identical &= all(np.array_equal(result[name], reference.record[:, k]) for k, name in enumerate(reference.names))
        ours.append(result.meta["loop_cpu_seconds"] / steps)
        theirs.append(c_seconds / steps)
        ratios.append(ours[-1] / theirs[-1])
    return {"ratios": ratios, "us_per_step": min(ours) * 1e6, "c_us_per_step": min(theirs) * 1e6,
            "identical": bool(identical)}


def measure(seconds: float = 5.0, repeats: int = 3) -> dict:
    """Every benchmark figure as a dict: runs of ``seconds`` simulated, ``repeats`` of each.

    Returns
    -------
    dict
        ``open_loop_over_c`` and ``closed_loop_over_c`` (median ratio of CPU times), their
        ``*_spread`` (lowest, highest), the µs per step of each loop, ``rtf_open_loop``,
        ``rtf_closed_loop`` and ``rtf_closed_loop_c`` (simulated over CPU seconds, best run),
        ``*_identical``, then the batch-path figures of :func:`quadcosim.benchmarks.estimators.measure` and
        the FMI shell's cost, :func:`quadcosim.benchmarks.fmu_steps.measure` (``fmu_step_over_equations``).
    """
    figures = {}
    for key, scenario, settings in (("open_loop", "open-loop", {}), ("closed_loop", "tp", CLOSED_LOOP)):
        run = compare(scenario, settings, seconds, repeats)
        figures |= {f"{key}_over_c": statistics.median(run["ratios"]),
                    f"{key}_over_c_spread": [min(run["ratios"]), max(run["ratios"])],
                    f"{key}_us_per_step": run["us_per_step"], f"{key}_c_us_per_step": run["c_us_per_step"],
                    f"rtf_{key}": 1e3 / run["us_per_step"], f"rtf_{key}_c": 1e3 / run["c_us_per_step"],
                    f"{key}_identical": run["identical"]}
    return estimators.measure(seconds, repeats) | fmu_steps.measure(seconds, repeats) | figures | save_figures()


def main(argv=None) -> int:
    """``quadcosim bench`` with the arguments ``argv``; prints the figures and returns 0; raises a
    :class:`~quadcosim.infra.errors.UsageError` for a refused option (exit 2), a
    :class:`~quadcosim.infra.errors.RunError` when the figure could not be written (exit 1)."""
    import argparse

    from quadcosim.infra.errors import RunError, UsageError

    parser = argparse.ArgumentParser(prog="quadcosim bench", description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--seconds", type=float, default=5.0, help="simulated seconds per measurement")
    parser.add_argument("--repeats", type=int, default=3, help="measurements of each loop")
    parser.add_argument("--out", help="also draw the figures: a PNG, SVG or PDF file, or a folder (bench.png)")
    args = parser.parse_args(argv)
    if not MIN_SECONDS <= args.seconds <= MAX_SECONDS:  # NaN too
        raise UsageError(f"--seconds {args.seconds:g}: give the simulated time of each timed run, from "
                         f"{MIN_SECONDS:g} s ({MIN_SECONDS / 1e-3:g} macro steps) to {MAX_SECONDS:g} s (default 5)")
    if args.repeats < 1:
        raise UsageError(f"--repeats {args.repeats}: give 1 or more")
    path = None
    if args.out:
        from quadcosim.infra.files import figure_file

        path = figure_file(args.out, "bench.png", None)  # refused (OutputRefused) before minutes of timing
    figures = measure(args.seconds, args.repeats)
    if args.json:
        print(json.dumps(figures))
    else:
        for key, value in figures.items():
            print(f"{key:28s} {value:12.4g}" if isinstance(value, float) else f"{key:28s} {value}")
    if path is not None:
        try:
            print(f"figure: {draw(figures, path)}", file=sys.stderr if args.json else sys.stdout)
        except (OSError, ValueError) as error:  # a disk that filled: the figures above are the measurement
            raise RunError(f"the figure was not written: {error}") from error
    return 0


#: The range of ``--seconds``: at least enough macro steps for a time per step, at most an hour.
MIN_SECONDS, MAX_SECONDS = 0.01, 3600.0


#: The loops :func:`draw` sets side by side: label, the orchestrator's key, the C reference's key.
DRAWN_LOOPS = (("open loop\n(three FMUs)", "open_loop_us_per_step", "open_loop_c_us_per_step"),
               ("closed loop tp\n(FMUs, filter, controller)", "closed_loop_us_per_step", "closed_loop_c_us_per_step"),
               ("three fmi2DoStep\n(FMI against equations)", "fmu_steps_us", "equations_steps_us"))


def draw(figures: dict, path) -> Path:
    """The figures of :func:`measure` as bars: µs per macro step of each loop, the orchestrator
    (or the FMUs) beside its C reference, the ratio above; and the batch path's million filter
    updates per second.

    Parameters
    ----------
    figures : dict
        :func:`measure`'s result.
    path : str or pathlib.Path
        PNG, SVG or PDF file.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    import matplotlib.pyplot as plt

    from quadcosim.infra.files import headless_backend, save_figure

    headless_backend()
    fig, (steps, batch) = plt.subplots(1, 2, figsize=(10.0, 3.8), layout="constrained",
                                       gridspec_kw={"width_ratios": (3, 2)})
    x = np.arange(len(DRAWN_LOOPS))
    ours = [figures[key] for _, key, _ in DRAWN_LOOPS]
    theirs = [figures[key] for _, _, key in DRAWN_LOOPS]
    steps.bar(x - 0.2, ours, 0.4, label="orchestrator (Python, C chunks) / FMUs")
    steps.bar(x + 0.2, theirs, 0.4, label="C reference / equations called from C")
    for k, (a, b) in enumerate(zip(ours, theirs, strict=True)):
        steps.annotate(f"x {a / b:.2f}", (k, max(a, b)), xytext=(0, 3), textcoords="offset points", ha="center",
                       fontsize=8)
    steps.set_xticks(x, [label for label, _, _ in DRAWN_LOOPS], fontsize=8)
    steps.set_ylabel("CPU time per macro step (µs)")
    steps.set_ylim(0, 1.25 * max(ours + theirs))
    steps.legend(fontsize=8, loc="upper left")
    steps.set_title("stepping loops, same models, same data", loc="left", fontsize=9)
    names = ("numba,\none thread", "C,\none thread", f"numba,\n{figures.get('parallel_threads', 2)} threads")
    rates = [figures[key] / 1e6 for key in ("batch_updates_per_s", "batch_c_updates_per_s",
                                            "parallel_batch_updates_per_s")]
    batch.bar(range(3), rates, 0.6, color=["C0", "C1", "C2"])
    batch.set_xticks(range(3), names, fontsize=8)
    batch.set_ylabel("million filter updates per second")
    batch.set_title("batch path, explicit filter", loc="left", fontsize=9)
    for ax in (steps, batch):
        ax.grid(True, axis="y", alpha=0.3)
    try:
        return save_figure(fig, Path(path), dpi=120)
    finally:
        plt.close(fig)


if __name__ == "__main__":  # the same as quadcosim bench master
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim bench master").run, main)
