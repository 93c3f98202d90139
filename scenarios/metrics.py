"""What every ``metrics.json`` states besides a scenario's own numbers: units, the signals kept.

A metric's unit is read from the end of its name (``rms_error_deg``, ``bias_convergence_s``,
``rate_rad_s``); a scenario's report may add a ``units`` dictionary for names that carry none.
An option's unit is the first parenthesised unit of its help text (``"simulated time (s)"``).
"""

from __future__ import annotations

import functools
import re

#: Name endings and the unit they stand for, longest first.
SUFFIX_UNITS = (("_deg_times_s", "deg s"), ("_rad_s2", "rad/s^2"), ("_rad_s", "rad/s"), ("_deg_s", "deg/s"),
                ("_rad2", "rad^2"),
                ("_m_s", "m/s"), ("_deg", "deg"), ("_rad", "rad"), ("_uT", "uT"), ("_hz", "Hz"), ("_Hz", "Hz"),
                ("_ms", "ms"), ("_mm", "mm"), ("_s", "s"), ("_m", "m"), ("_A", "A"), ("_v", "V"), ("_V", "V"),
                ("_bytes", "B"), ("_mb", "MB"), ("_pct", "%"))

#: The units of an injected fault's fields (:func:`quadcosim.scenarios.fault_record`), as ``metrics.json`` states them.
FAULT_UNITS = "start, stop: s (stop null: no end); value: the target's unit (scale: a factor)"

_PARENTHESES = re.compile(r"\(([^()]*)\)")
_UNIT_WORD = re.compile(r"[A-Za-zµ%]+")
#: Unit symbols an option's help may use; a word outside them is prose, not a unit.
UNIT_SYMBOLS = {"s", "ms", "Hz", "deg", "rad", "m", "kg", "N", "A", "V", "W", "T", "uT", "µT", "Ohm", "C", "K",
                "h", "min", "Ah", "J", "g", "%", "dB", "mA", "rpm"}


def unit_of_name(name: str) -> str | None:
    """The unit a metric's name ends with (``"rms_error_deg"`` -> ``"deg"``), or None."""
    for suffix, unit in SUFFIX_UNITS:
        if name.endswith(suffix):
            return unit
    return None


def option_unit(help_text: str) -> str | None:
    """The unit of an option: the first parentheses of its help text that hold one.

    ``"macro step (s)"`` -> ``"s"``; ``"bias gain (1/s^2); lab: the lab's value"`` -> ``"1/s^2"``;
    ``"accelerometer weight (1; Mahony's Kp = kP k1)"`` -> ``"1"``; None when no parentheses
    hold a unit (prose, a file name, a list of values).

    Parameters
    ----------
    help_text : str
        The option's help.

    Returns
    -------
    str or None
        The unit, as written there.
    """
    for match in _PARENTHESES.finditer(help_text):
        unit = match[1].split(";")[0].strip()
        words = _UNIT_WORD.findall(unit)
        if unit and len(unit) <= 12 and "," not in unit and " " not in unit and all(w in UNIT_SYMBOLS for w in words):
            if words or unit == "1":
                return unit
    return None


def metric_units(metrics: dict, declared: dict | None = None) -> dict[str, str]:
    """Unit of each top-level metric: from its name, or as the report ``declared`` it.

    Parameters
    ----------
    metrics : dict
        The metrics, by name.
    declared : dict, optional
        Units the report gives for names that carry none (``{"bias_error_final": "rad/s"}``).

    Returns
    -------
    dict of str to str
        Metric name to unit, for the metrics whose unit is known.
    """
    units = {name: unit for name in metrics if (unit := unit_of_name(name))}
    return units | {k: v for k, v in (declared or {}).items() if k in metrics}


def recorded_outputs(system, left_out=()) -> list[str]:
    """Every output of ``system`` but the tie-offs of ``System.set_input`` and ``left_out``
    (names or vector names such as ``"Quadrotor.R"``)."""
    names = tuple(f"{b.name}.{y}" for b in system.blocks.values() if not getattr(b, "ties", None) for y in b.outputs)
    return list(_kept(names, tuple(left_out)))


@functools.lru_cache(maxsize=64)
def _kept(names: tuple[str, ...], left_out: tuple[str, ...]) -> tuple[str, ...]:
    """``names`` but the members of ``left_out``; the same systems come back run after run."""
    from quadcosim.orchestrator.signals import expand

    dropped = {member for name in left_out for member in expand(name, names)}
    return tuple(n for n in names if n not in dropped)
