"""``quadcosim sweep`` and ``quadcosim sweep-plot`` (also ``python -m quadcosim.studies.sweep``).

    quadcosim sweep tp --grid k=0.01:10:log12 --grid estimator=linear,explicit \\
        --set duration=5 --seeds 4 --workers 2 --out results/k-sweep
    quadcosim sweep tp --out results/k-sweep --resume
    quadcosim sweep tp ... --scheduler tcp://192.168.1.10:8786
    quadcosim sweep-plot results/k-sweep "rms_error_deg[0]" --x k --by estimator
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from quadcosim.infra.errors import UsageError, refusals


def add_arguments(p: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Add the options of ``quadcosim sweep`` to the parser ``p``; return it."""
    p.add_argument("scenario", help="a scenario (quadcosim list) or a named sweep (lab-matrix)")
    p.add_argument("--grid", action="append", default=[], metavar="NAME=SPEC",
                   help="vary an option: a,b,c | start:stop:logN | start:stop:linN | start:stop (integers)")
    p.add_argument("--set", action="extend", nargs="+", default=[], metavar="NAME=VALUE",
                   help="fix options (several after one flag) or block parameters (IMU.gyro_noise_density=0.001)")
    p.add_argument("--seeds", metavar="N|A:B", help="Monte Carlo: the seed option over 1..N (or A..B)")
    p.add_argument("--workers", type=int, metavar="N", help="local worker processes (default: the CPUs)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="use a running Dask scheduler (tcp://host:8786)")
    p.add_argument("--connect-timeout", type=float, default=10.0, metavar="S",
                   help="seconds to reach the --scheduler before giving up (default 10)")
    p.add_argument("--out", help="sweep folder (default results/sweep-SCENARIO, or results/sweep-SCENARIO-N when that "
                                 "holds an earlier sweep)")
    p.add_argument("--resume", action="store_true", help="continue the sweep in --out; skip finished members")
    p.add_argument("--retries", type=int, default=2, metavar="N",
                   help="resubmissions of a member whose worker died (default 2)")
    p.add_argument("--retry-errors", action="store_true",
                   help="also retry members that raised or gave a NaN (members are deterministic)")
    p.add_argument("--results", action="store_true", help="keep each member's results and figures (large)")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    from quadcosim.studies.sweep.grid import MAX_MEMBERS

    p.add_argument("--max-members", type=int, default=MAX_MEMBERS, metavar="N",
                   help=f"refuse a plan of more members (default {MAX_MEMBERS:,}); counted before any is made")
    return p


def add_plot_arguments(p: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Add the options of ``quadcosim sweep-plot`` to the parser ``p``; return it."""
    p.add_argument("table", help="a sweep folder, or its sweep.parquet / sweep.csv")
    p.add_argument("metric", help="a metric column, e.g. 'rms_error_deg[0]'")
    p.add_argument("--x", required=True, help="the option along the horizontal axis")
    p.add_argument("--by", help="the option whose values make the curves")
    p.add_argument("--out", help="PNG or SVG file (default METRIC-vs-X.png in the sweep folder)")
    p.add_argument("--logy", action="store_true", help="logarithmic metric axis")
    return p


def _stored_plan(out: Path):
    from quadcosim.studies.sweep.grid import Plan, stored_members

    path = out / "sweep.json"
    try:
        stored = json.loads(path.read_text())
        return Plan(stored["scenario"], stored_members(stored), stored["varied"], stored["description"],
                    stored.get("name"))
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise ValueError(f"{path} is unreadable ({type(error).__name__}: {error}); its sweep cannot be resumed: "
                         "run it again into another --out") from None


def default_out(base: Path, resume: bool, label: str, marker: str = "sweep.json") -> Path:
    """The folder a sweep writes into when ``--out`` is not given: ``base``, or, when that holds
    an earlier sweep and this is not a ``--resume``, the next free ``base-2``, ``base-3``, ...,
    said on standard error (as ``quadcosim run`` does: a sweep never meets an earlier one unasked).

    Parameters
    ----------
    base : pathlib.Path
        The default folder (``results/sweep-tp``).
    resume : bool
        A resumed sweep continues in ``base``.
    label : str
        The command, for the message.
    marker : str
        The file whose presence means a folder holds an earlier study (``tune.json`` for a tune).

    Returns
    -------
    pathlib.Path
    """
    if resume:
        return base
    from quadcosim.infra.files import first_free

    candidate = first_free(base, lambda folder: (folder / marker).exists()
                           or (folder.exists() and not folder.is_dir()))
    if candidate != base:
        print(f"{label}: {base}/ holds an earlier {marker.split('.')[0]}; writing to {candidate}/ (--out DIR "
              f"chooses the folder, --resume continues {base}/)", file=sys.stderr)
    return candidate


def make_plan(args):
    """The plan the parsed arguments ``args`` describe (a named sweep, a grid, or the stored one
    on --resume)."""
    from quadcosim.studies.sweep import grid, named

    out = Path(args.out) if args.out else default_out(Path("results") / f"sweep-{args.scenario}", args.resume,
                                                      f"quadcosim sweep {args.scenario}")
    args.out = str(out)
    if args.resume and not (out / "sweep.json").exists():
        raise ValueError(f"--resume: {out} holds no sweep (no sweep.json); run the sweep without --resume to "
                         "start it, or give the --out of an earlier sweep")
    if args.resume and not (args.grid or args.set or args.seeds):
        plan = _stored_plan(out)
        if args.scenario not in (plan.scenario, plan.name):
            raise ValueError(f"{out} holds a sweep of {plan.name or plan.scenario}, not {args.scenario}")
        return plan
    sweeps = named.registry()
    if args.scenario in sweeps:
        if args.grid or args.seeds:
            raise ValueError(f"{args.scenario} is a named sweep: its members are fixed; only --set applies")
        return sweeps[args.scenario].plan(args.set)
    return grid.plan(args.scenario, args.grid, args.set, args.seeds, max_members=args.max_members)


def sweep(args) -> int:
    """Run ``quadcosim sweep`` from parsed arguments ``args``; print the summary.

    Returns
    -------
    int
        Exit code (:data:`quadcosim.studies.sweep.engine.EXIT_CODES`): 0 when every member is ``ok``, 1
        when any failed or was not run, 2 for bad arguments or a refused folder, 3 when every
        member ran and some diverged, 128 + the signal when interrupted.
    """
    from quadcosim.studies.sweep import engine, named

    with refusals(failures=()):  # SweepError is a ValueError: exit 2
        if args.workers is not None and args.workers < 1:
            raise ValueError(f"--workers {args.workers}: give at least 1")
        if args.workers and args.scheduler:
            raise ValueError("--workers and --scheduler: the scheduler's own workers run the sweep; give one")
        if args.max_members < 1:
            raise ValueError(f"--max-members {args.max_members}: give at least 1 (the most members a plan may have)")
        if not args.connect_timeout > 0:
            raise ValueError(f"--connect-timeout {args.connect_timeout:g}: give a number of seconds above 0")
        from quadcosim.studies.sweep.folder import check_out, check_scheduler

        check_scheduler(args.scheduler)  # before the plan is made or anything written
        if args.out:
            check_out(Path(args.out))
        plan = make_plan(args)
        if not args.quiet:
            print(f"sweep {plan.name or plan.scenario}: {len(plan.members)} members"
                  + (f" over {', '.join(plan.varied)}" if plan.varied else "") + f", into {args.out}/",
                  file=sys.stderr)
        summary = engine.run(plan, args.out, workers=args.workers, scheduler=args.scheduler, resume=args.resume,
                             retries=args.retries, retry_errors=args.retry_errors,
                             keep_results=args.results or named.keep_results(plan),
                             progress=False if args.quiet else None,
                             extra_metrics=named.extra_metrics(plan), connect_timeout=args.connect_timeout)
    written = named.summarise(plan, args.out, summary)
    print(summary.text())
    if written is not None:  # a named sweep's own tables and checks (lab-matrix's summary.md)
        print(written.read_text())
    return summary.exit_code()


def _plot_context(folder: Path) -> tuple[dict, str, dict]:
    """Units of the swept scenario's options and block parameters (as declared), a line naming the scenario and
    the options held fixed, and what its metrics' components are (``rms_error_deg[0]``: roll),
    from the sweep's ``sweep.json`` (nothing without one)."""
    from quadcosim.studies.sweep import units as units_of

    from quadcosim import scenarios

    try:
        stored = json.loads((folder / "sweep.json").read_text())
        scenario = scenarios.get(stored["scenario"])
    except (OSError, ValueError, KeyError):
        return {}, "", {}
    units = stored.get("units") or units_of.of_options(stored["scenario"], [*scenario.options,
                                                                             *stored.get("varied", [])])
    fixed = stored.get("description", {}).get("set") or []
    components = {f"{metric}[{i}]": name for metric, names in scenario.extra.get("components", {}).items()
                  for i, name in enumerate(names)}
    return (units, f"{stored.get('name') or stored['scenario']} sweep" + (f"; {', '.join(fixed)}" if fixed else ""),
            components)


def sweep_plot(args) -> int:
    """Run ``quadcosim sweep-plot`` from parsed arguments ``args``; print the figure's path.

    Returns
    -------
    int
        Exit code: 0, 2 for a missing table or column or a figure path refused, 1 for a full disk.
    """
    from quadcosim.studies.sweep import figure, table

    with refusals():  # a missing column or a figure path refused: exit 2; a full disk: exit 1, nothing left
        try:
            columns = table.read(args.table)
        except FileNotFoundError as error:
            raise UsageError(f"no sweep table at {error.filename}: give a sweep folder (--out of quadcosim sweep) "
                             "or its sweep.parquet / sweep.csv") from None
        source = Path(args.table)
        folder = source if source.is_dir() else source.parent
        safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in f"{args.metric}-vs-{args.x}")
        units, subtitle, components = _plot_context(folder)
        path = figure.plot(columns, args.metric, args.x, by=args.by, logy=args.logy,
                           out=args.out or folder / f"{safe}.png", units=units, subtitle=subtitle,
                           components=components)
    print(path)
    return 0


def main(argv=None) -> int:
    """``python -m quadcosim.studies.sweep``: the same parser and work as ``quadcosim sweep``;
    returns its exit code, its errors printed (2 when refused).

    Parameters
    ----------
    argv : list of str, optional
        The arguments (default ``sys.argv[1:]``).
    """
    from quadcosim.infra.command import Command

    def parsed_and_run(argv):
        p = add_arguments(argparse.ArgumentParser(prog="python -m quadcosim.studies.sweep", description=__doc__,
                                                  formatter_class=argparse.RawDescriptionHelpFormatter))
        return sweep(p.parse_args(argv))

    return Command("quadcosim sweep").run(parsed_and_run, argv)
