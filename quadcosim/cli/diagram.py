"""``quadcosim diagram SCENARIO``: a picture of a scenario's wiring."""

from __future__ import annotations

from pathlib import Path

from quadcosim.cli.run import _settings
from quadcosim.infra.errors import refusals


def add(sub) -> None:
    """Add the ``diagram`` verb to the sub-parsers ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``quadcosim`` parser's sub-parsers.
    """
    diagram = sub.add_parser("diagram", help="draw the wiring of a scenario")
    diagram.add_argument("scenario", help="a scenario name (quadcosim list shows them)")
    diagram.add_argument("--set", action="extend", nargs="+", default=[], metavar="KEY=VALUE",
                         help="scenario options or block parameters, as for run (the wiring may depend on them: "
                              "magnetic=on adds the motors' field)")
    diagram.add_argument("--estimator", metavar="MODULE:CLASS", help="your own estimator block (as for run)")
    diagram.add_argument("--out", help="PNG or SVG file (default results/SCENARIO/diagram.png; a folder takes "
                         "diagram.png)")
    diagram.set_defaults(func=command)


def command(args) -> int:
    """Build the scenario's system and draw its wiring; print the figure's path. A refused option
    or output path raises before anything is written; a full disk leaves nothing under the
    figure's name.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed ``diagram`` arguments.
    """
    from quadcosim.infra.progress import reporting, status

    with reporting(True):
        status(f"quadcosim diagram {args.scenario}: loading the packages")
        from quadcosim import scenarios
        from quadcosim.orchestrator.diagram import draw

        with refusals(failures=()):
            scenario = scenarios.get(args.scenario)
            options = scenario.parse(_settings(args))
            status(f"{args.scenario}: building the system (its FMUs loaded)")
            system = scenario.system(options)
        from quadcosim.infra.files import figure_file
        from quadcosim.orchestrator.diagram import blocks_text

        status(f"{args.scenario}: drawing the wiring ({blocks_text(system)})")
        with refusals():  # an output path refused (before anything is written), a full disk
            out = figure_file(args.out, "diagram.png", Path("results") / args.scenario)
            path = draw(system, out, scenario.title(options))
    print(path)
    return 0
