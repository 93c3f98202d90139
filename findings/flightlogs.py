"""Findings of the real flights: the quad's two compasses calibrated from its three flights
(each model's explained share of the held-out residual, the perturbation at hover and the
heading change), the exported parameter file of every compass of every ArduPilot log scored as
its firmware applies it against the log as flown, what each wrong firmware rule costs that export
(an ablation), and the estimators replayed on every shared
log without and with the compensation, against the autopilot's attitude.

The logs (three flights of one quad, an Erle-Brain flight and a PX4 bench log) are read from
the folder that ``$QUADCOSIM_FLIGHT_LOGS`` names; without it the group is skipped
(``FileNotFoundError``). The commands name them as they sit in a folder ``logs/``.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

FOLDER_VARIABLE = "QUADCOSIM_FLIGHT_LOGS"  # the folder holding the logs
FLIGHTS = {"a": "quad_2015-10-11_19-53-46.log", "b": "quad_2015-10-11_19-59-09.log",
           "c": "quad_2015-10-11_20-17-22.log"}
COMPASSES = {0: "external", 1: "internal"}
MODELS = ("current", "throttle", "motors", "metge")
REPLAYS = [("a", 0), ("a", 1), ("b", 0), ("b", 1), ("c", 0), ("c", 1), ("erlebrain", 0), ("px4", 0)]
OTHER_LOGS = {"erlebrain": "erlebrain_APM_22.bin", "px4": "px4_sample.ulg"}
# every compass of every ArduPilot log: its export against the log as flown (one column per judge)
EXPORTS = [("a", 0), ("a", 1), ("b", 0), ("b", 1), ("c", 0), ("c", 1), ("erlebrain", 0)]
REPLAYED = ("explicit", "vqf")
# the internal compass of the three quad flights and the Erle-Brain's: what each wrong firmware rule costs
ABLATIONS = [("a", 1), ("b", 1), ("c", 1), ("erlebrain", 0)]
ABLATION = "python -m findings flightlogs"  # a function of the group, not a command's output
PERCENT = 100.0
# the means over the flights: the group prints them (and, with --check, writes nothing)
MEANS = "python -m findings flightlogs --check"


def _name(key: str) -> str:
    return FLIGHTS.get(key) or OTHER_LOGS[key]


def _shown(key: str) -> str:
    """The log as a command names it, from the repository's root."""
    return f"logs/{_name(key)}"


def _path(key: str) -> Path:
    folder = os.environ.get(FOLDER_VARIABLE)
    if not folder:
        raise FileNotFoundError(f"the flight logs are absent: set {FOLDER_VARIABLE} to their folder")
    path = Path(folder) / _name(key)
    if not path.exists():
        raise FileNotFoundError(f"{path}: the flight log is absent from {FOLDER_VARIABLE}")
    return path


def _finding(name, value, unit, command, tolerance, digits) -> dict:
    return {"name": f"flightlogs.{name}", "value": float(value), "unit": unit, "command": command,
            "tolerance": float(tolerance), "digits": int(digits)}


def _calibrate_command(files, compass: int, cross: bool) -> str:
    if cross:
        return (f"quadcosim calibrate --train {' '.join(_shown(f) for f in files[:-1])} --test "
                f"{_shown(files[-1])} --compass {compass} --out results/flightlogs")
    return f"quadcosim calibrate {_shown(files[0])} --compass {compass} --out results/flightlogs"


def _calibrations(flights, compasses, models, cross: bool) -> list[dict]:
    """Each flight's last half scored on a fit to its first half (and, with ``cross``, each
    flight scored on a fit to the two others)."""
    from quadcosim.calibration.flight import calibrate
    from quadcosim.flightlogs import read_log
    from quadcosim.scenarios.flightlog.calibrate import split_parts

    logs = {k: read_log(_path(k)) for k in flights}
    found = []
    for compass in compasses:
        where = f"quad.{COMPASSES[compass]}"
        hover, change = {m: [] for m in models}, {m: [] for m in models}
        for key in logs:
            split = split_parts([logs[key]], [], compass)  # as the command splits it, the Earth field model attached
            metrics, _, _ = calibrate(split.train, split.test, models)
            for m in models:
                result = metrics["models"][m]
                if "refused" in result:
                    continue
                found.append(_finding(f"{where}.{m}.explained_half_{key}", PERCENT * result["explained_test"], "%",
                                      _calibrate_command([key], compass, False), 0.5, 0))
                hover[m].append(result["perturbation_at_hover_T"] * 1e6)
                change[m].append(result["heading_rms_change_deg"])
            if cross:
                others = [k for k in logs if k != key]
                split = split_parts([logs[k] for k in others], [logs[key]], compass)
                metrics, _, _ = calibrate(split.train, split.test, models)
                for m in models:
                    if "refused" not in metrics["models"][m]:
                        found.append(_finding(f"{where}.{m}.explained_cross_{key}",
                                              PERCENT * metrics["models"][m]["explained_test"], "%",
                                              _calibrate_command([*others, key], compass, True), 0.5, 0))
        for m in models:
            if hover[m]:
                found.append(_finding(f"{where}.{m}.hover_uT", np.mean(hover[m]), "uT",
                                      MEANS, 0.05, 1))
                found.append(_finding(f"{where}.{m}.heading_change_deg", np.mean(change[m]), "deg",
                                      MEANS, 0.05, 1))
    return found


def export_command(key: str, compass: int) -> str:
    """The command that exports compass ``compass`` of log ``key`` and prints its scores."""
    return f"quadcosim calibrate {_shown(key)} --compass {compass} --out results/flightlogs"


def _exports(keys) -> list[dict]:
    """Each compass's exported file and the log as flown, scored on the last half as the log's
    firmware applies them (heading error, deg RMS; explained share, %), through the command itself."""
    import contextlib
    import io
    import json
    import tempfile

    from quadcosim.scenarios.flightlog.calibrate import main as calibrate

    found = []
    for key, compass in keys:
        with tempfile.TemporaryDirectory() as folder, contextlib.redirect_stdout(io.StringIO()), \
                contextlib.redirect_stderr(io.StringIO()):
            calibrate([str(_path(key)), "--compass", str(compass), "--out", folder, "--overwrite"])
            export = json.loads((Path(folder) / "metrics.json").read_text())["export"]
        command = export_command(key, compass)
        name = f"export.{key}{compass}"
        found.append(_finding(f"{name}.as_flown_deg", export["as_flown"]["heading_rms_deg"], "deg", command, 0.02, 2))
        found.append(_finding(f"{name}.export_deg", export["heading_rms_deg"], "deg", command, 0.02, 2))
        found.append(_finding(f"{name}.explained_pct", PERCENT * export["explained_test"], "%", command, 0.2, 1))
    return found


def _ablations() -> list[dict]:
    """The heading error (deg RMS, score part) of the export under the right rules and under each
    wrong one, applied as the log's firmware applies it (:mod:`findings.flightlog_ablation`)."""
    from quadcosim.flightlogs import read_log

    from findings.flightlog_ablation import costs

    found = []
    for key, compass in ABLATIONS:
        for rule, value in costs(read_log(_path(key)), compass).items():
            found.append(_finding(f"ablation.{key}{compass}.{rule}_deg", value, "deg", ABLATION, 0.02, 2))
    return found


def _replays() -> list[dict]:
    from quadcosim.scenarios.flightlog.replay import replay_log

    found = []
    for key, compass in REPLAYS:
        result = replay_log(_path(key), compass, kinds=REPLAYED)
        command = f"quadcosim log replay {_shown(key)} --compass {compass}"
        for kind in REPLAYED:
            for label in ("without", "with"):
                r = result["estimators"][kind][label]
                name = f"replay.{key}{compass}.{kind}.{label}"
                found.append(_finding(f"{name}.heading_deg", r["heading_rms_deg"], "deg", command, 0.05, 1))
                found.append(_finding(f"{name}.inclination_deg", r["inclination_rms_deg"], "deg", command, 0.05, 1))
    return found


def compute(quick: bool = False) -> list[dict]:
    """The group's findings (see the module docstring); ``quick``: flight b's internal compass,
    current and throttle models, last half held out (a few seconds)."""
    if quick:
        return [f for f in _calibrations(["b"], [1], ("current", "throttle"), cross=False)
                if ".explained_half_" in f["name"]] + _exports([("b", 1)])
    return (_calibrations(list(FLIGHTS), list(COMPASSES), MODELS, cross=True) + _exports(EXPORTS) + _ablations()
            + _replays())
