"""Findings of the peer: MAVExplorer's ``magfit``, the field's own fitting code, run on the same
split as quadcosim's export, for every compass of every shared ArduPilot log: fitted on the export's
fit part (the flight's first half), its setting chosen on the choice part (the third quarter), and
the parameters it prints scored on the score part (the last quarter) exactly as the export is
scored (``quadcosim calibrate LOG --compass N --score FILE``: the file loaded on top of the log's
parameters and applied as the log's firmware applies it).

How it is run: MAVProxy's ``MAVProxy.modules.lib.magfit.magfit(mlog, timestamp_in_range)``, the
function MAVExplorer's ``magfit`` panel calls when its *Run* button is pressed, with the panel's
options (``margs``) and its own way of restricting the log to a time range (the plot's limits;
here the fit part). The module imports wxPython only for the panel: it is imported with a
stand-in for ``wx`` (nothing of it is used by the fit) and without letting its plotting helper
switch matplotlib to the wx backend; its figure is saved to a file, as its own headless ``main``
does. Two of the panel's settings are run: its defaults (offsets; scale held at 1) and with
*Elliptical* checked (offsets, diagonal and off-diagonal soft iron, within the panel's default
bounds); the one with the lower heading error on the choice part is magfit's column. Its
motor-current fit (*CMOT*) reads the current from ``BAT`` messages, which the shared logs (Copter
3.4) do not have (they log ``CURR``).

magfit cannot run without a 3D GPS fix in the part it is given: it takes the Earth field, its
target, from the World Magnetic Model at that fix. Such a compass is reported with the reason.

MAVProxy is an optional extra (``pip install "quadcosim[peers]"``): without it the group is
skipped, saying so. The logs are read from ``$QUADCOSIM_FLIGHT_LOGS`` (see
:mod:`findings.flightlogs`).
"""

from __future__ import annotations

import contextlib
import io
import json
import re
import sys
import tempfile
import types
from pathlib import Path

from findings import Skipped
from findings.flightlogs import EXPORTS, _path, _shown

MAVPROXY = "1.8.75"  # the MAVProxy release whose magfit is run (pinned in the `peers` extra)
INSTALL = 'pip install "quadcosim[peers]"'
#: magfit's settings: the panel's defaults, and with its Elliptical box checked
SETTINGS = {"offsets": {"Elliptical": False}, "elliptical": {"Elliptical": True}}
#: MAVExplorer's magfit panel's default values (MAVProxy/modules/lib/magfit.py, MagFitUI.init_ui)
PANEL = {"Attitude": "ATT", "Lattitude": 0.0, "Longitude": 0.0, "BatteryNum": 1, "Reduce": 1, "Offsets": True,
         "OffsetMax": 1500, "ScaleMin": 1.0, "ScaleMax": 1.0, "Elliptical": False, "DiagonalMin": 0.8,
         "DiagonalMax": 1.2, "OffDiagMin": -0.2, "OffDiagMax": 0.2, "CMOT": False, "CMOT NoChange": False,
         "CMOT Max": 10.0}
# the findings print their values; this command prints them all (and, with --check, writes nothing)
COMMAND = "python -m findings magfit --check"
PRINTED = re.compile(r"^(COMPASS_\w+) (-?\d+(?:\.\d+)?)$")


def require_mavproxy() -> None:
    """Raise :class:`Skipped`, naming the install command, when MAVProxy is absent or not the pinned release."""
    from importlib import metadata

    try:
        version = metadata.version("MAVProxy")
    except metadata.PackageNotFoundError:
        raise Skipped(f"MAVProxy is not installed: {INSTALL} (MAVProxy {MAVPROXY})") from None
    if version != MAVPROXY:
        raise Skipped(f"MAVProxy {version} is installed, the findings are of {MAVPROXY}: {INSTALL}")


def magfit_module():
    """MAVProxy's ``magfit`` module, imported without wxPython (only its panel needs it).

    Raises
    ------
    Skipped
        MAVProxy is not installed, or not the pinned release.
    """
    require_mavproxy()
    import matplotlib

    absent, use = "wx" not in sys.modules, matplotlib.use
    if absent:  # the panel's base class is all the module takes from wx at import
        sys.modules["wx"] = types.SimpleNamespace(Dialog=object)
    matplotlib.use = lambda *args, **kwargs: None  # its grapher would switch to the WXAgg backend
    try:
        from MAVProxy.modules.lib import magfit
    finally:
        matplotlib.use = use
        if absent:
            del sys.modules["wx"]
    return magfit


def _message(name: str) -> tuple[str, int | None]:
    """The DataFlash message of a compass named as the log names it (``MAG2``, ``MAG[1]``) and its instance."""
    match = re.fullmatch(r"(\w+)\[(\d+)\]", name)
    return (match.group(1), int(match.group(2))) if match else (name, None)


def _seconds(msg) -> float:
    return msg.TimeUS * 1e-6 if hasattr(msg, "TimeUS") else msg.TimeMS * 1e-3


def training_span(mlog, compass_name: str, start: float, end: float):
    """MAVExplorer's time-range test (``timestamp_in_range``) for the compass samples between
    ``start`` and ``end``.

    The range opens just after the last sample before ``start``, so that the attitude logged before
    the first sample of the range is seen, and closes at the last sample of the range.

    Parameters
    ----------
    mlog : pymavlink DFReader
        The log, as ``mavutil.mavlink_connection`` opens it (rewound on return).
    compass_name : str
        The compass as the log names it (``MAG``, ``MAG2``, ``MAG[1]``).
    start, end : float
        The range (s, the log's clock, as :class:`quadcosim.calibration.flight.FlightData` holds it).

    Returns
    -------
    (callable, int)
        The test (a message's ``_timestamp`` to -1 before the range, 0 in it, 1 after) and the
        number of compass samples in the range.
    """
    message, instance = _message(compass_name)
    mlog.rewind()
    before, first, last, count = None, None, None, 0
    while (msg := mlog.recv_match(type=[message])) is not None:
        if instance is not None and getattr(msg, "I", 0) != instance:
            continue
        t = _seconds(msg)
        if t < start:
            before = msg._timestamp
        elif t <= end:
            first = msg._timestamp if first is None else first
            last, count = msg._timestamp, count + 1
    mlog.rewind()
    if first is None:
        raise ValueError(f"no {compass_name} sample between {start} s and {end} s")
    opens = first if before is None else 0.5 * (before + first)

    def in_range(timestamp: float) -> int:
        return -1 if timestamp < opens else 1 if timestamp > last else 0

    return in_range, count


def cannot_run(mlog, in_range) -> str | None:
    """Why magfit cannot fit on the part of ``mlog`` that ``in_range`` selects, or None: it needs
    the ``AHRS_TRIM`` parameters and a 3D GPS fix there (its Earth field)."""
    missing = [n for n in ("AHRS_TRIM_X", "AHRS_TRIM_Y", "AHRS_TRIM_Z") if n not in mlog.params]
    if missing:
        return f"the log has no {', '.join(missing)} parameter, which magfit adds to the attitude"
    mlog.rewind()
    fix = False
    while (msg := mlog.recv_match(type=["GPS"])) is not None:
        where = in_range(msg._timestamp)
        if where > 0:
            break
        if where == 0 and msg.Status >= 3:
            fix = True
            break
    mlog.rewind()
    if not fix:
        return ("no GPS fix in the fit part: magfit's target is the World Magnetic Model's field at a 3D fix, "
                "and the log has none")
    return None


def run_magfit(path, compass_name: str, orientation: int, in_range, setting: str) -> tuple[dict, str]:
    """MAVExplorer's magfit on the compass ``compass_name`` of the log at ``path``, on the part
    ``in_range`` selects, with the panel's defaults and ``SETTINGS[setting]``.

    Parameters
    ----------
    path : path-like
        The DataFlash log (.bin or text .log).
    compass_name : str
        The compass as the log names it (``MAG``, ``MAG2``, ``MAG[1]``), as magfit's *Magnetometer*.
    orientation : int
        The compass's ``COMPASS_ORIENT``: the panel's default, so that magfit rotates nothing.
    in_range : callable
        :func:`training_span`'s range test.
    setting : str
        A key of :data:`SETTINGS`.

    Returns
    -------
    (dict, str)
        The parameters magfit prints (name: value, in ArduPilot's units, as printed) and all it printed.
    """
    from pymavlink import mavutil

    magfit = magfit_module()
    magfit.margs = PANEL | SETTINGS[setting] | {
        "Magnetometer": compass_name, "Orientation": magfit.RotationIDToString(int(orientation))}
    # module state: the field and corrections of the previous run must not carry over
    magfit.earth_field, magfit.old_corrections = None, magfit.Correction()
    mlog = mavutil.mavlink_connection(str(path))
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed), tempfile.TemporaryDirectory() as folder:
        magfit.magfit(mlog, in_range, save_plot=str(Path(folder) / "magfit.png"))
    import matplotlib.pyplot as pyplot

    pyplot.close("all")
    text = printed.getvalue()
    params = {m.group(1): float(m.group(2)) for line in text.splitlines() if (m := PRINTED.match(line.strip()))}
    return params, text


def _orientation(params: dict, slot: int) -> int:
    return int(params.get("COMPASS_ORIENT" + ("" if slot == 0 else str(slot + 1)), 0))


def peer(key: str, compass: int, settings=tuple(SETTINGS)) -> dict:
    """magfit on the export's fit part of compass ``compass`` of log ``key`` (the same split as
    ``quadcosim calibrate``: :func:`quadcosim.scenarios.flightlog.calibrate.split_parts`), each of
    ``settings`` scored on the choice part (:func:`quadcosim.calibration.flight.export.score_parameters`, as
    the export's groups are chosen) and on the score part by ``quadcosim calibrate --score``.

    Returns
    -------
    dict
        Per setting: ``heading_rms_deg`` and ``explained`` on the score part, ``choice_heading_rms_deg``
        on the choice part, ``params`` (as magfit prints them), ``points`` (samples magfit used) and
        ``samples`` (in the fit part); ``chosen``: the setting with the lower heading error on the
        choice part; ``as_flown`` on the score part. Or ``cannot_run``: the reason.
    """
    require_mavproxy()  # skips before any work when MAVProxy is absent
    from pymavlink import mavutil
    from quadcosim.calibration.flight.export import score_parameters
    from quadcosim.flightlogs import read_log
    from quadcosim.flightlogs.autopilots.ardupilot import write as write_ardupilot
    from quadcosim.scenarios.flightlog.calibrate import main as calibrate
    from quadcosim.scenarios.flightlog.calibrate import split_parts

    path = _path(key)
    mlog = mavutil.mavlink_connection(str(path))
    reason = cannot_run(mlog, lambda timestamp: 0)  # the whole log: nothing to split when it cannot run at all
    if reason is not None:
        return {"cannot_run": reason.replace("in the fit part", "in the log")}
    split = split_parts([read_log(path)], [], compass)  # as the command splits it
    (part,) = split.fit
    chosen = part.log.compasses[compass]
    in_range, count = training_span(mlog, chosen.name, float(part.time[0]), float(part.time[-1]))
    reason = cannot_run(mlog, in_range)
    if reason is not None:
        return {"cannot_run": reason}
    found = {}
    with tempfile.TemporaryDirectory() as folder:
        for setting in settings:
            params, text = run_magfit(path, chosen.name, _orientation(part.log.params, chosen.slot), in_range, setting)
            if not params:
                return {"cannot_run": f"magfit printed no parameters: {text.strip().splitlines()[-1:]}"}
            points = int(re.search(r"Extracted (\d+) points", text).group(1))
            file = Path(folder) / f"magfit-{setting}.parm"
            write_ardupilot(params, file)
            out = Path(folder) / setting
            with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
                code = calibrate([str(path), "--compass", str(compass), "--score", str(file), "--out", str(out)])
            if code:
                raise RuntimeError(f"quadcosim calibrate --score {file} failed on {path} (exit {code})")
            metrics = json.loads((out / "metrics.json").read_text())
            choice = score_parameters(split.choice, params, offset_from=split.fit)["heading_rms_deg"]
            found[setting] = metrics["score"] | {"choice_heading_rms_deg": choice, "params": params,
                                                 "points": points, "samples": count}
            found["as_flown"] = metrics["as_flown"]
    found["chosen"] = min(settings, key=lambda s: found[s]["choice_heading_rms_deg"])
    return found


def _finding(name, value, unit, tolerance, digits) -> dict:
    return {"name": f"magfit.{name}", "value": float(value), "unit": unit, "command": COMMAND,
            "tolerance": float(tolerance), "digits": int(digits)}


def findings_of(key: str, compass: int, settings=tuple(SETTINGS)) -> list[dict]:
    """The findings of one compass: each setting's heading error (deg RMS) on the score part, its
    file applied as the log's firmware applies it, and that of the setting chosen on the choice
    part; none where magfit cannot run (the docs say why).

    Parameters
    ----------
    key : str
        The log's key in :mod:`findings.flightlogs` (``a``, ``b``, ``c``, ``erlebrain``).
    compass : int
        The compass, from 0 in the log's order.
    settings : tuple of str
        Keys of :data:`SETTINGS` to run.
    """
    result = peer(key, compass, settings)
    if "cannot_run" in result:
        print(f"magfit cannot run on {_shown(key)} compass {compass}: {result['cannot_run']}", file=sys.stderr)
        return []
    chosen = result[result["chosen"]]["heading_rms_deg"]
    return [_finding(f"{key}{compass}.{setting}_deg", result[setting]["heading_rms_deg"], "deg", 0.02, 2)
            for setting in settings] + [_finding(f"{key}{compass}.chosen_deg", chosen, "deg", 0.02, 2)]


def compute(quick: bool = False) -> list[dict]:
    """The group's findings (see the module docstring); ``quick``: flight b's internal compass with
    the panel's defaults (about half a minute)."""
    if quick:  # the choice between settings needs both: the quick subset has none
        return [f for f in findings_of("b", 1, ("offsets",)) if f["name"].endswith(".offsets_deg")]
    return [f for key, compass in EXPORTS for f in findings_of(key, compass)]
