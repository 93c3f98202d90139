"""What a flight log holds, as a dictionary and as the text of ``quadcosim log info``."""

from __future__ import annotations

import numpy as np
from quadcosim.flightlogs.model import FlightLog, rate


def summary(log: FlightLog) -> dict:
    """Sensors (instances, samples, rates in Hz, mean field norm in T, mean specific-force norm
    in m/s^2), duration (s), the span every sensor covers (``common_span_s``, s on the log's
    clock, None when they share none), vehicle, firmware, simulator flag, the log's own statement
    that it is synthetic (empty for a recording) and current sensor of ``log``."""
    from quadcosim.flightlogs.checks import common_span

    span = common_span(log)
    compasses = [{"index": k, "name": c.name, "samples": len(c.time), "rate_hz": rate(c.time),
                  "external": c.external, "field_norm_T": float(np.median(np.linalg.norm(c.field, axis=1))),
                  "raw_source": c.raw_source, "setup": dict(c.setup)} for k, c in enumerate(log.compasses)]
    imus = [{"name": i.name, "samples": len(i.time), "rate_hz": rate(i.time),
             "acc_norm_m_s2": float(np.median(np.linalg.norm(i.acc, axis=1)))} for i in log.imus]
    motors = None if log.motors is None else {
        "count": log.motors.commands.shape[1], "rate_hz": rate(log.motors.time),
        "pwm_limits_us": [log.motors.pwm_min, log.motors.pwm_max], "limits_from": log.motors.limits_from,
        "throttle_range": [float(log.motors.throttle.min()), float(log.motors.throttle.max())]}
    battery = None if log.battery is None else {
        "rate_hz": rate(log.battery.time),
        "voltage_range_V": [float(log.battery.voltage.min()), float(log.battery.voltage.max())],
        "current_range_A": None if log.battery.current is None else [float(log.battery.current.min()),
                                                                     float(log.battery.current.max())],
        "current_sensor": log.battery.current_sensor}
    return {"file": log.path, "format": log.format, "autopilot": log.autopilot, "firmware": log.firmware,
            "vehicle": log.vehicle, "simulator": log.simulator, "synthetic": log.synthetic, "duration_s": log.duration,
            "common_span_s": None if span is None else list(span),
            "compasses": compasses, "imus": imus, "motors": motors, "battery": battery,
            "current_sensor": log.battery is not None and log.battery.current is not None,
            "attitude": None if log.attitude is None else {"source": log.attitude.source,
                                                          "rate_hz": rate(log.attitude.time)},
            "parameters": len(log.params),
            "parameters_changed": sorted(n for n, v in log.defaults.items() if n in log.params and log.params[n] != v)
            if log.defaults else None, "warnings": list(log.warnings)}


def text(info: dict) -> str:
    """The ``summary`` dictionary ``info`` as the lines ``quadcosim log info`` prints."""
    origin = (info["synthetic"] if info.get("synthetic") else
              "SIMULATOR log" if info["simulator"] else "real hardware")
    lines = [f"{info['file']}: {info['format']}, {info['autopilot']} {info['firmware']}",
             f"  vehicle: {info['vehicle']}; {origin}; {info['duration_s']:.1f} s; {info['parameters']} parameters"
             + ("" if info.get("parameters_changed") is None else
                f" ({len(info['parameters_changed'])} set away from the firmware's defaults)")]
    span = info["common_span_s"]
    lines.append("  sensors together: none (their time stamps do not overlap)" if span is None else
                 f"  sensors together: {span[1] - span[0]:.1f} s ({span[0]:.1f} to {span[1]:.1f} s on the log's clock)")
    for c in info["compasses"]:
        where = {True: "external", False: "internal", None: "location not logged"}[c["external"]]
        lines.append(f"  compass {c['index']} {c['name']}: {c['samples']} samples at {c['rate_hz']:.1f} Hz, {where}, "
                     f"|field| {c['field_norm_T'] * 1e6:.1f} uT")
        if c.get("setup"):
            lines.append("    " + "; ".join(f"{name.replace('_', ' ')} {value}" for name, value in c["setup"].items()))
    if not info["compasses"]:
        lines.append("  compass: none logged")
    for i in info["imus"]:
        lines.append(f"  IMU {i['name']}: {i['samples']} samples at {i['rate_hz']:.1f} Hz, "
                     f"|specific force| {i['acc_norm_m_s2']:.2f} m/s2")
    m = info["motors"]
    lines.append("  motors: none logged" if m is None else
                 f"  motors: {m['count']} at {m['rate_hz']:.1f} Hz, PWM {m['pwm_limits_us'][0]:.0f}..."
                 f"{m['pwm_limits_us'][1]:.0f} us ({m['limits_from']}), throttle {m['throttle_range'][0]:.2f} to "
                 f"{m['throttle_range'][1]:.2f}")
    b = info["battery"]
    if b is None:
        lines.append("  battery: none logged; current sensor: no")
    else:
        current = ("no" if b["current_range_A"] is None
                   else f"yes, {b['current_range_A'][0]:.1f} to {b['current_range_A'][1]:.1f} A")
        lines.append(f"  battery: {b['voltage_range_V'][0]:.2f} to {b['voltage_range_V'][1]:.2f} V at "
                     f"{b['rate_hz']:.1f} Hz; current sensor: {current} ({b['current_sensor']})")
    a = info["attitude"]
    lines.append("  attitude: none logged" if a is None else f"  attitude: {a['source']} at {a['rate_hz']:.1f} Hz")
    lines += [f"  warning: {w}" for w in info["warnings"]]
    return "\n".join(lines)
