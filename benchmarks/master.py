"""Benchmark of the co-simulation master (``quadcosim bench``).

Measures, in one run:
- the orchestrator on the ``open-loop`` scenario at 1 kHz (three FMUs, scripted commands,
  every output recorded at every step);
- a hand-written minimal loop on the same three FMUs with the same connections, the same
  command table and the same recording, calling the FMI functions directly through ctypes
  with preallocated arguments (the fastest per-call path found here);
- their ratio, and the real-time factor of the orchestrator.
Times are of the stepping loop only (instantiation excluded), best of ``repeats``.
"""

from __future__ import annotations

import ctypes
import json
import sys
import time

import numpy as np

from benchmarks import estimators


def orchestrator_us_per_step(seconds: float, repeats: int) -> float:
    """Microseconds per step of the master on ``open-loop`` over ``seconds`` simulated, best of ``repeats``."""
    import scenarios

    scenario = scenarios.get("open-loop")
    options = scenario.parse({"duration": seconds})
    best = np.inf
    for _ in range(repeats):
        result = scenario.build(options).run(seconds)
        best = min(best, result.meta["loop_seconds"] / (len(result) - 1))
    return best * 1e6


def _at(array: np.ndarray, index: int = 0) -> ctypes.c_void_p:
    """Address of ``array[index]``, as a ctypes argument."""
    return ctypes.c_void_p(array.ctypes.data + array.itemsize * index)


def raw_us_per_step(seconds: float, repeats: int) -> float:
    """Microseconds per step of the hand-written ctypes loop (best of ``repeats``)."""
    from orchestrator.fmu import FMUInstance
    from scenarios.open_loop import commands

    void, size = ctypes.c_void_p, ctypes.c_size_t
    steps = int(round(seconds / 1e-3))
    table = commands(seconds, 1e-3, 0.01)
    best = np.inf
    for _ in range(repeats):
        motors, body, imu = FMUInstance("MotorMagnetics"), FMUInstance("Quadrotor"), FMUInstance("IMU")
        keep = []  # the value reference arrays the ctypes arguments point into

        def refs(fmu, names, keep=keep):
            array = fmu.vr(names)
            keep.append(array)
            return void(array.ctypes.data), size(len(array))

        m_out, q_out, i_out = (np.zeros(len(f.outputs)) for f in (motors, body, imu))
        record = np.empty((steps + 1, len(m_out) + len(q_out) + len(i_out)))
        m_in_vr, m_in_n = refs(motors, ["c1", "c2", "c3", "c4"])
        m_vr, m_n = refs(motors, motors.outputs)
        q_in_vr, q_in_n = refs(body, ["omega_r1", "omega_r2", "omega_r3", "omega_r4"])
        q_vr, q_n = refs(body, body.outputs)
        i_in_vr, i_in_n = refs(imu, ["q0", "q1", "q2", "q3", "omega_x", "omega_y", "omega_z", "f_x", "f_y", "f_z"])
        i_bd_vr, i_bd_n = refs(imu, ["b_d_x", "b_d_y", "b_d_z"])
        i_vr, i_n = refs(imu, imu.outputs)
        omega_r = _at(m_out, motors.outputs.index("omega_r1"))
        b_d = _at(m_out, motors.outputs.index("b_d_x"))
        q = _at(q_out, body.outputs.index("q0"))
        rows = [_at(table, 4 * k) for k in range(len(table))]
        ms, mg, md, mc = motors.raw_set_real, motors.raw_get_real, motors.raw_do_step, motors.component_arg
        qs, qg, qd, qc = body.raw_set_real, body.raw_get_real, body.raw_do_step, body.component_arg
        is_, ig, id_, ic = imu.raw_set_real, imu.raw_get_real, imu.raw_do_step, imu.component_arg
        m_ptr, q_ptr, i_ptr = _at(m_out), _at(q_out), _at(i_out)
        a, b = len(m_out), len(m_out) + len(q_out)
        now, h, one = ctypes.c_double(0.0), ctypes.c_double(1e-3), ctypes.c_int(1)
        started = time.perf_counter()
        for n in range(steps + 1):
            ms(mc, m_in_vr, m_in_n, rows[n])
            mg(mc, m_vr, m_n, m_ptr)
            qs(qc, q_in_vr, q_in_n, omega_r)
            qg(qc, q_vr, q_n, q_ptr)
            is_(ic, i_in_vr, i_in_n, q)
            is_(ic, i_bd_vr, i_bd_n, b_d)
            ig(ic, i_vr, i_n, i_ptr)
            record[n, :a] = m_out
            record[n, a:b] = q_out
            record[n, b:] = i_out
            if n == steps:
                break
            now.value = n * 1e-3
            md(mc, now, h, one)
            qd(qc, now, h, one)
            id_(ic, now, h, one)
        best = min(best, (time.perf_counter() - started) / steps)
        for fmu in (motors, body, imu):
            fmu.close()
    return best * 1e6


def measure(seconds: float = 5.0, repeats: int = 3) -> dict:
    """Every benchmark figure as a dict: runs of ``seconds`` simulated, best of ``repeats``."""
    orchestrator = orchestrator_us_per_step(seconds, repeats)
    raw = raw_us_per_step(seconds, repeats)
    figures = {
        "orchestrator_us_per_step": orchestrator,
        "raw_us_per_step": raw,
        "overhead_ratio": orchestrator / raw,
        "rtf_open_loop": 1e3 / orchestrator,
    }
    return figures | estimators.measure(seconds, repeats)


def main(argv=None) -> int:
    """``quadcosim bench`` with the arguments ``argv``; prints the figures and returns 0."""
    import argparse

    parser = argparse.ArgumentParser(prog="quadcosim bench", description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--seconds", type=float, default=5.0, help="simulated seconds per measurement")
    parser.add_argument("--repeats", type=int, default=3, help="measurements, best kept")
    args = parser.parse_args(argv)
    figures = measure(args.seconds, args.repeats)
    if args.json:
        print(json.dumps(figures))
    else:
        for key, value in figures.items():
            print(f"{key:28s} {value:12.4g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
