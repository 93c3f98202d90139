"""``quadcosim log info FILE``, ``quadcosim log plot FILE``: what a flight log holds, in text and in
one figure; ``quadcosim log replay FILE``: the estimators on it (:mod:`quadcosim.scenarios.flightlog.replay`);
``quadcosim log example FOLDER``: three synthetic logs to try them on."""

from __future__ import annotations

import json
from pathlib import Path

from quadcosim.scenarios.flightlog.reading import load

from quadcosim.infra.errors import refusals


def info(args) -> int:
    """``quadcosim log info FILE [--json]`` (``args`` from :func:`add_arguments`); a bad log raises
    :class:`~quadcosim.flightlogs.LogError` (exit 2)."""
    from quadcosim.flightlogs.info import summary, text

    found = summary(load(args.file, "log info"))
    print(json.dumps(found, indent=2) if args.json else text(found))
    return 0


def plot(args) -> int:
    """``quadcosim log plot FILE [--out FIGURE]`` (``args`` from :func:`add_arguments`); a bad log
    or output path raises a :class:`~quadcosim.infra.errors.UsageError` (exit 2), a figure that
    could not be written (a full disk) a :class:`~quadcosim.infra.errors.RunError` (exit 1)."""
    from quadcosim.scenarios.flightlog.overview import plot_overview

    from quadcosim.infra.files import figure_file

    with refusals(usage=()):  # a full disk (named, nothing left), a folder removed under it
        out = figure_file(args.out, f"{Path(args.file).stem}-overview.png", Path("results") / "logs")
        if not args.out and not args.overwrite:
            from quadcosim.scenarios.output_options import free_file

            out = free_file(out, "log plot")
        log = load(args.file, "log plot")
        print(plot_overview(log, out))
    return 0


def replay(args) -> int:
    """``quadcosim log replay FILE`` (``args`` from :func:`add_arguments`, handed to
    :func:`quadcosim.scenarios.flightlog.replay.run`), imported when called: the estimators (and numba)
    load for a replay, not for every command's parser."""
    from quadcosim.scenarios.flightlog import replay as replayed

    return replayed.run(args)


def add_arguments(parser):
    """The ``log`` verb's sub-commands on ``parser`` (an argparse parser); returns it."""
    sub = parser.add_subparsers(dest="log_command", required=True)
    shown = sub.add_parser("info", help="what the log holds: sensors, rates, duration, vehicle, firmware, "
                           "simulator or not, current sensor or not")
    shown.add_argument("file", help="PX4 .ulg, ArduPilot .bin or .log")
    shown.add_argument("--json", action="store_true", help="print the summary as JSON on standard output, in "
                       "place of the text")
    shown.set_defaults(func=info)
    drawn = sub.add_parser("plot", help="an overview figure: field, current, throttle and attitude")
    drawn.add_argument("file", help="PX4 .ulg, ArduPilot .bin or .log")
    drawn.add_argument("--out", help="figure file to write, .png, .svg or .pdf (default "
                       "results/logs/NAME-overview.png, or the next free -N name; a folder takes "
                       "NAME-overview.png)")
    drawn.add_argument("--overwrite", action="store_true",
                       help="replace results/logs/NAME-overview.png rather than take the next free name")
    drawn.set_defaults(func=plot)
    replayed = sub.add_parser("replay", help="the project's estimators on the log, without and with the "
                              "compensation, against the autopilot's attitude (a reference, not the truth)")
    replayed.add_argument("file", help="PX4 .ulg, ArduPilot .bin or .log")
    replayed.add_argument("--compass", type=int, default=0, help="compass to use, from 0 in the log's order")
    from quadcosim.scenarios.output_options import add_json_flag

    add_json_flag(replayed, "print the result as JSON on standard output, in place of the table")
    replayed.add_argument("--out", metavar="FILE", help="also write the result to this JSON file")
    replayed.set_defaults(func=replay)
    from quadcosim.scenarios.flightlog import example

    made = sub.add_parser("example", help="write three small synthetic flight logs to try these commands on "
                          "(ArduPilot text logs: example-a.log, example-b.log, example-c.log)")
    made.add_argument("out", help="folder to write them into (created)")
    made.add_argument("--seconds", type=float, default=40.0, metavar="S", help="length of each flight (s, default 40)")
    made.set_defaults(func=example.command)
    return parser
