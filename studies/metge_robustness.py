"""How far the motor-field compensation holds on plants its model family does not contain.

``quadcosim run metge`` calibrates on a rig whose motors, ESCs and cables are exactly those the
identified family can describe (:mod:`quadcosim.calibration.identify`: a first-order motor with back-EMF,
free-wheeling or not, a current limit, one field gain per cable), so its free-set error is a best
case. Here each case calibrates on one plant (set 1: a full and a half-used battery, rising
sweeps) and scores the compensation on the free set of another:

- the family does not contain the plant: a winding inductance 10 and 30 times the default (the
  family has no electrical lag), a regenerative ESC (calibrated on rising sweeps alone, where
  it never brakes);
- the plant drifts between calibration and flight: warmer windings (resistance +30 %),
  weaker magnets (back-EMF constant -5 %), a cable moved (every field gain +10 %), an older
  battery (internal resistance x3).

``python -m quadcosim.studies.metge --robustness --out DIR`` writes ``robustness.json`` and prints the
table; :func:`study` does it from Python.
"""

from __future__ import annotations

from quadcosim.fmus import vehicle
from quadcosim.scenarios.metge import (
    RECORD,
    SCENARIO,
    RigRun,
    RigSet,
    calibrate,
    commands,
    errors_deg,
    fast_third,
    parse_orders,
    set_error,
    socs,
    system_for,
)

INDUCTANCE_FACTORS = (10.0, 30.0)  # 1, winding inductance over the default's
WARM_RESISTANCE = 1.3  # 1, winding resistance in flight over the calibration's
WEAK_MAGNETS = 0.95  # 1, back-EMF constant in flight over the calibration's
MOVED_CABLE = 1.1  # 1, every cable's field gain in flight over the calibration's
OLD_BATTERY = 3.0  # 1, battery internal resistance in flight over the calibration's


def _scaled(name: str, nominal, factor: float) -> dict:
    return {f"MotorMagnetics.{name}": nominal * factor}


def cases() -> dict[str, tuple[str, dict, dict]]:
    """Case name -> (description, settings of the calibration plant, settings of the flight plant)."""
    out = {"nominal": ("the plant the family contains (quadcosim run metge, calibration 1)", {}, {})}
    for factor in INDUCTANCE_FACTORS:
        plant = _scaled("L_m", vehicle.MOTOR_INDUCTANCE, factor)
        out[f"inductance_x{factor:g}"] = (f"winding inductance x{factor:g} (no electrical lag in the family)",
                                          plant, plant)
    regenerative = {"MotorMagnetics.regenerative": True}
    out["regenerative"] = ("regenerative ESC, calibrated on rising sweeps", regenerative, regenerative)
    moved = {f"MotorMagnetics.kappa{n + 1}": g * MOVED_CABLE for n, g in enumerate(vehicle.MOTOR_FIELD_GAIN)}
    out |= {"warm_windings": (f"winding resistance x{WARM_RESISTANCE:g} in flight", {},
                              _scaled("R_m", vehicle.MOTOR_RESISTANCE, WARM_RESISTANCE)),
            "weak_magnets": (f"back-EMF constant x{WEAK_MAGNETS:g} in flight", {},
                             _scaled("k_e", vehicle.MOTOR_KE, WEAK_MAGNETS)),
            "moved_cable": (f"every field gain x{MOVED_CABLE:g} in flight", {}, moved),
            "old_battery": (f"battery resistance x{OLD_BATTERY:g} in flight", {},
                            _scaled("R_b", vehicle.BATTERY_RESISTANCE, OLD_BATTERY))}
    return out


def case_errors(calibration_plant: dict, flight_plant: dict, settings: dict | None = None) -> dict:
    """Calibrate on one plant (calibration set 1), score on the free set of another.

    Parameters
    ----------
    calibration_plant, flight_plant : dict
        ``{"MotorMagnetics.NAME": value}`` of each plant (empty: the default vehicle).
    settings : dict, optional
        Other ``metge`` options (defaults: the scenario's).

    Returns
    -------
    dict
        ``sets_deg`` (mean error on set 1's settled rows after eq. 9, calibration plant),
        ``free_eq9_deg``, ``free_dynamic_deg`` and ``free_dynamic_fast_deg`` (mean errors on
        the flight plant's free set, and on its fast third, deg), ``freewheel`` and
        ``exponent`` (the structure identified).
    """
    o = SCENARIO.parse(dict(settings or {}) | calibration_plant)
    rate = o["mag_rate"]
    runs = [RigRun(system_for(o, 1, run).run(commands(o, 1, free=run == 0)[2], record=RECORD), o, 1)
            for run in range(len(socs(o, 1)))]
    cal = calibrate(RigSet(runs), parse_orders(o["orders"]) or (4, 1), None, rate, "set 1")
    first = runs[0]
    if flight_plant != calibration_plant:
        flight = SCENARIO.parse(dict(settings or {}) | flight_plant)
        first = RigRun(system_for(flight, 1, 0).run(commands(flight, 1, free=True)[2], record=RECORD), flight, 1)
    eq9 = errors_deg(cal, first, "metge", rate)[first.free]
    dynamic = errors_deg(cal, first, "dynamic", rate)[first.free]
    return {"sets_deg": set_error(cal, RigSet(runs), "metge", rate, "settled"), "free_eq9_deg": float(eq9.mean()),
            "free_dynamic_deg": float(dynamic.mean()),
            "free_dynamic_fast_deg": float(dynamic[fast_third(first, o)].mean()),
            "freewheel": bool(cal.dynamics.freewheel), "exponent": int(cal.dynamics.exponent)}


def study(out=None, names=None) -> dict:
    """Every case of :func:`cases` (or those named), printed as it comes and written to
    ``out/robustness.json`` when ``out`` is given.

    Parameters
    ----------
    out : str or pathlib.Path, optional
        Output folder.
    names : sequence of str, optional
        Cases to run (default all).

    Returns
    -------
    dict
        Case name -> :func:`case_errors` and its ``description``.
    """
    from pathlib import Path

    from quadcosim.infra.files import write_json

    table = {}
    for name, (description, calibration_plant, flight_plant) in cases().items():
        if names and name not in names:
            continue
        table[name] = {"description": description, **case_errors(calibration_plant, flight_plant)}
        row = table[name]
        print(f"{name:16s} sets {row['sets_deg']:6.3f}  free eq.9 {row['free_eq9_deg']:6.3f}  free dynamic "
              f"{row['free_dynamic_deg']:6.3f}  fast third {row['free_dynamic_fast_deg']:6.3f} deg  "
              f"(identified: {'free-wheeling' if row['freewheel'] else 'regenerative'}, exponent {row['exponent']})"
              f"  {description}", flush=True)
    if out is not None:
        Path(out).mkdir(parents=True, exist_ok=True)
        write_json(Path(out) / "robustness.json", table)
    return table
