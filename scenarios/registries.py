"""The package's closed sets of names as Markdown tables, read from their registries.

- the estimators, the entry-point group ``quadcosim.estimators`` (:func:`quadcosim.estimators.kinds.registry`);
- the interference models a flight calibration fits, :func:`quadcosim.calibration.flight.catalogue.models`
  (entry-point group ``quadcosim.interference``);
- the autopilots whose logs are read and whose parameters the export writes,
  :func:`quadcosim.flightlogs.autopilots.registry` (entry-point group ``quadcosim.autopilots``);
- the scenarios, :mod:`quadcosim.scenarios.catalogue` (entry-point group ``quadcosim.scenarios``);
- the sensor FMUs, :data:`quadcosim.fmus.MODELS` (the entry-point group ``quadcosim.sensors``).

The documentation's page of these sets is :func:`tables`, written when the site is built: a
member added by its registry line is listed there as in ``quadcosim list`` and the command
line's choices.
"""

from __future__ import annotations


def _yes(flag: bool) -> str:
    return "yes" if flag else ""


def _row(cells) -> str:
    return "| " + " | ".join(str(cell).replace("|", "\\|") for cell in cells) + " |"


def _table(header, rows) -> list[str]:
    return [_row(header), _row(["---"] * len(header)), *(_row(row) for row in rows), ""]


def estimator_rows() -> list[tuple]:
    """One row per estimator: name, label, lab filter, gyro bias, closed loop, recorded arrays,
    compared, its own block (none: :class:`quadcosim.estimators.QuaternionEstim` builds it by name)."""
    from quadcosim.estimators.kinds import registry

    return [(f"`{kind.name}`", kind.label, _yes(kind.lab), _yes(kind.bias), _yes(kind.streaming), _yes(kind.batch),
             "" if kind.compared is None else ", ".join(f"{k}={v}" for k, v in kind.compared.items()) or "yes",
             f"`{kind.block}`" if kind.block else "")
            for kind in registry().values()]


def model_rows() -> list[tuple]:
    """One row per interference model, richest first: name, rank, calibration file, an autopilot."""
    from quadcosim.calibration.flight.catalogue import models

    ordered = sorted(models().values(), key=lambda model: model.preference)
    return [(f"`{model.name}`", model.preference, _yes(model.in_file), _yes(model.autopilot)) for model in ordered]


def autopilot_rows() -> list[tuple]:
    """One row per autopilot: name, the log formats it reads (by name and description), the parameter
    file written, whether ``--firmware`` chooses among its versions, its module."""
    from quadcosim.flightlogs.autopilots import registry

    from quadcosim.infra.members import registered

    lines = registered("quadcosim.autopilots")
    return [(autopilot.name, ", ".join(f"`{f.name}` ({f.description})" for f in autopilot.formats),
             f"`{autopilot.file}`", _yes(autopilot.versions is not None), f"`{lines[name][0].split(':')[0]}`")
            for name, autopilot in registry().items()]


def scenario_rows() -> list[tuple]:
    """One row per registered scenario: name, description, module (imports every scenario)."""
    from quadcosim.scenarios.catalogue import registrations, registry

    modules = registrations()
    return [(f"`{name}`", scenario.description, f"`{modules[name][0]}`") for name, scenario in registry().items()]


def sensor_rows() -> list[tuple]:
    """One row per sensor FMU: name, states, integrator, default sub-step, the package of its folder
    (each model's ``SUMMARY`` and table, :mod:`quadcosim.fmus.models`)."""
    from quadcosim.fmus.build import table
    from quadcosim.fmus.models import sensors

    rows = []
    for name, member in sensors().items():
        summary = member.check("SUMMARY")
        sub_step = next((v.start for v in table(name).of("parameter") if v.name == "sub_step"), None)
        rows.append((f"`{name}`", summary["states"], summary["integrator"],
                     "—" if sub_step is None else f"{sub_step * 1e3:g} ms", f"`{member.module}`"))
    return rows


def sensor_table() -> str:
    """The sensor FMUs as one Markdown table (the documentation's guide to the FMUs includes it)."""
    return "\n".join(_table(("FMU", "states", "integrator", "default sub-step", "folder (package)"), sensor_rows()))


def tables() -> str:
    """The four sets as one Markdown page (a heading, then a table per set)."""
    lines = ["# What the package names", "",
             "Generated from the registries when the site is built; each set is extended by one line in the "
             "module named (see {doc}`../guides/maintainers`).", "",
             "## Estimators", "", "The entry-point group `quadcosim.estimators` (`pyproject.toml`, one line per "
             "estimator naming its module's `Kind`), read by a scenario's `estimator` choices, the comparisons "
             "and the replays. Columns: one of the lab's filters (gains `k1`, `k2`, `kP`, `kI`); a gyro bias "
             "estimated; runs in a closed loop; runs on recorded arrays (the batch path); in the comparisons (with "
             "these settings); its own block (without one, `quadcosim.estimators.QuaternionEstim` builds the "
             "filter by its "
             "name).", ""]
    lines += _table(("name", "label", "lab", "bias", "loop", "batch", "compared", "block"),
                    estimator_rows())
    lines += ["## Interference models", "", "Entry-point group `quadcosim.interference` (protocol: "
              "`calibration/flight/catalogue.py`), richest first: `quadcosim calibrate "
              "--models`, the calibration file and the autopilots' parameters carry the first they can that the "
              "flights identify. An autopilot carries a model when its firmware has that compensation for the "
              "compass (`motors`: ArduPilot `4.0` and later, first compass).", ""]
    lines += _table(("name", "rank", "calibration file", "an autopilot"), model_rows())
    lines += ["## Autopilots", "", "Entry-point group `quadcosim.autopilots` (protocol: "
              "`flightlogs/autopilots/__init__.py`): a log is read by the autopilot whose format claims its first "
              "bytes, and a flight log of one is exported in its own parameter file.", ""]
    lines += _table(("name", "log formats", "parameter file", "firmware versions", "module"), autopilot_rows())
    lines += ["## Scenarios", "", "`scenarios/catalogue.py` (and `register` from a higher floor): `quadcosim run`, "
              "`quadcosim list`, sweeps.", ""]
    lines += _table(("name", "description", "module"), scenario_rows())
    lines += ["## Sensor FMUs", "", "The entry-point group `quadcosim.sensors` (`pyproject.toml`), a folder each: "
              "`quadcosim build`, `quadcosim list --parameters`, the orchestrator's `--set`, the twins and the FMU "
              "checks.", "", sensor_table()]
    return "\n".join(lines)
