"""The README's findings: every number it states, measured by code and kept in ``findings.json``.

A *group* is a module ``findings.<group>`` with ``compute(quick: bool = False) ->
list[dict]``; each dict is one finding:

- ``name``: dotted, starting with the group (``flight.tilt.accelerometer_tilt_deg``);
- ``value`` (float), ``unit`` (str);
- ``command``: the shell command a user runs to see the number (it prints it);
- ``tolerance``: absolute, in ``unit``: how far a re-run may move the value before a test fails;
- ``digits``: decimals the README prints.

``quick=True`` returns the subset of a group's findings that is computed in well under a minute,
with the same values (CI compares them with the committed ones). A group whose data are absent
(a dataset not shipped) raises :class:`Skipped` (a ``FileNotFoundError`` counts the same): it is
reported as skipped, and its committed values are kept.

Adding a group is one line in :data:`GROUPS`. ``python -m findings`` (or ``quadcosim
findings``) runs the groups, writes ``findings.json`` at the repository's root and rewrites the
README's numbers from it (:mod:`findings.readme`).
"""

from __future__ import annotations

import importlib
import json
import math
from pathlib import Path

#: Every group of findings, in the order they are run and listed; one line a group.
GROUPS = (
    "flight",
    "lab",
    "rig",
    "metge",
    "infrared",
    "gain_study",
    "gain_ablation",
    "speed",
    "isolation",
    "sweep_cost",
    "flightlogs",
    "magfit",
    "real_recordings",
    "plant",
    "fmu_agreement",
    "mag_rate",
    "records",
    "excerpt",
    "log_info",
    "example_replay",
    "ardupilot_logs",
    "compass_rate",
    "tune",
)

ROOT = Path(__file__).resolve().parents[1]
#: The committed findings, at the repository's root.
FINDINGS_FILE = ROOT / "findings.json"
KEYS = ("name", "value", "unit", "command", "tolerance", "digits")


class Skipped(Exception):
    """Raised by a group's ``compute`` when what it measures is absent (a dataset not shipped);
    the message says what is missing and how to get it."""


class FindingError(ValueError):
    """A finding is malformed, or a group returned something that is not a list of findings."""


def check(finding: dict, group: str) -> dict:
    """``finding`` checked: every key of :data:`KEYS`, a finite value, a non-negative tolerance,
    a name in its group.

    Parameters
    ----------
    finding : dict
        One finding, as a group's ``compute`` returns it.
    group : str
        The group that returned it.

    Returns
    -------
    dict
        The finding with ``value`` and ``tolerance`` as float, ``digits`` as int, and ``group``.

    Raises
    ------
    FindingError
        A missing key, a non-finite value, a negative tolerance, a name outside the group.
    """
    missing = [k for k in KEYS if k not in finding]
    if missing:
        raise FindingError(f"finding {finding.get('name', finding)!r} of group {group} lacks {', '.join(missing)}")
    name = finding["name"]
    if not str(name).startswith(f"{group}."):
        raise FindingError(f"finding {name!r} of group {group} must be named {group}.SOMETHING")
    value, tolerance, digits = float(finding["value"]), float(finding["tolerance"]), int(finding["digits"])
    if not math.isfinite(value):
        raise FindingError(f"finding {name}: value {value} is not finite")
    if not (tolerance >= 0 and math.isfinite(tolerance)):
        raise FindingError(f"finding {name}: tolerance {tolerance} must be finite and at least 0")
    return {"name": str(name), "value": value, "unit": str(finding["unit"]), "command": str(finding["command"]),
            "tolerance": tolerance, "digits": digits, "group": group}


def finding(name: str, value: float, unit: str, command: str, tolerance: float, digits: int) -> dict:
    """One finding as a dict of :data:`KEYS` (a shorthand for groups).

    Parameters
    ----------
    name : str
        Dotted, starting with the group.
    value : float
        The measured value, in ``unit``.
    unit : str
        Its unit (``"deg"``, ``"m/s"``, ``"1"`` for a ratio).
    command : str
        The command that prints it.
    tolerance : float
        How far a re-run may move it (absolute, in ``unit``).
    digits : int
        Decimals the README prints.
    """
    return {"name": name, "value": float(value), "unit": unit, "command": command, "tolerance": float(tolerance),
            "digits": int(digits)}


def command(prefix: str, settings: dict) -> str:
    """The command line of a finding: ``prefix`` and ``--set`` of ``settings`` as a user types them.

    Parameters
    ----------
    prefix : str
        ``"quadcosim run tp"``.
    settings : dict
        Options; booleans as ``on``/``off``, floats without trailing zeros.

    Returns
    -------
    str
        ``"quadcosim run tp --set flight=tilt tilt_deg=5"`` (``prefix`` alone without settings).
    """
    def text(value) -> str:
        if isinstance(value, bool):
            return "on" if value else "off"
        return f"{value:g}" if isinstance(value, float) else str(value)

    return prefix + (" --set " + " ".join(f"{k}={text(v)}" for k, v in settings.items()) if settings else "")


def compute_group(group: str, quick: bool = False) -> list[dict]:
    """The findings of ``group``, checked (:func:`check`).

    Parameters
    ----------
    group : str
        One of :data:`GROUPS`.
    quick : bool
        The group's fast subset.

    Returns
    -------
    list of dict

    Raises
    ------
    Skipped
        The group's data are absent.
    KeyError
        Not a group of :data:`GROUPS`.
    """
    if group not in GROUPS:
        raise KeyError(f"unknown findings group {group!r}; groups: {', '.join(GROUPS)}")
    module = importlib.import_module(f"findings.{group}")
    try:
        found = module.compute(quick=quick)
    except FileNotFoundError as missing:
        raise Skipped(f"data absent: {missing}") from missing
    if not isinstance(found, list):
        raise FindingError(f"findings.{group}.compute returned {type(found).__name__}, not a list")
    checked = [check(f, group) for f in found]
    names = [f["name"] for f in checked]
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise FindingError(f"group {group} returns {', '.join(repeated)} more than once")
    return checked


def load(path=FINDINGS_FILE) -> dict[str, dict]:
    """The committed findings, by name (empty if the file does not exist).

    Parameters
    ----------
    path : str or pathlib.Path
        A ``findings.json``.

    Returns
    -------
    dict
        Name -> finding (keys of :data:`KEYS` and ``group``).
    """
    path = Path(path)
    if not path.exists():
        return {}
    try:
        data = json.loads(path.read_text())
        return {f["name"]: f for f in data["findings"]}
    except (ValueError, KeyError, TypeError, OSError) as error:
        raise FindingError(f"{path}: not a findings file ({error}); regenerate it with "
                           "`python -m findings`") from None


def save(findings: dict[str, dict], path=FINDINGS_FILE) -> Path:
    """Write ``findings`` (name -> finding) to ``path`` atomically, sorted by group order then name."""
    from quadcosim.infra.files import write_json

    order = {g: i for i, g in enumerate(GROUPS)}
    rows = sorted(findings.values(), key=lambda f: (order.get(f["group"], len(order)), f["name"]))
    return write_json(path, {"about": "The README's numbers, measured by `python -m findings`; each "
                                      "`command` prints its value. tolerance: absolute, in unit; digits: decimals "
                                      "the README prints.",
                             "findings": [{k: f[k] for k in (*KEYS, "group")} for f in rows]})


def differences(computed: list[dict], committed: dict[str, dict]) -> list[str]:
    """What parts ``computed`` from ``committed``: a value moved by more than the committed
    tolerance, a finding new or no longer committed, a changed unit or digits.

    Parameters
    ----------
    computed : list of dict
        Findings just computed.
    committed : dict
        Name -> committed finding (:func:`load`).

    Returns
    -------
    list of str
        One line per difference; empty when they agree.
    """
    lines = []
    for f in computed:
        old = committed.get(f["name"])
        if old is None:
            lines.append(f"{f['name']}: {f['value']:.{f['digits']}f} {f['unit']} is not in findings.json")
            continue
        if abs(f["value"] - old["value"]) > old["tolerance"]:
            lines.append(f"{f['name']}: {f['value']!r} {f['unit']} computed, {old['value']!r} committed "
                         f"(tolerance {old['tolerance']:g}; command: {f['command']})")
        for key in ("unit", "digits"):
            if f[key] != old[key]:
                lines.append(f"{f['name']}: {key} {f[key]!r} computed, {old[key]!r} committed")
    return lines
