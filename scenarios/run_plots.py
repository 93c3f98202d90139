"""Figures of finished runs: ``quadcosim plot RUN SIGNAL...`` and ``quadcosim compare RUN RUN...
SIGNAL``.

A run is its folder (the ``--out`` of ``quadcosim run``, holding ``results.npz``) or the
``results.npz`` file itself. Signals are named as the run recorded them (``IMU.acc_x``), or by
vector (``IMU.acc``: its three components); a name the run left out is refused with the nearest
recorded names, and with the way to record it when the scenario left it out on purpose.
"""

from __future__ import annotations

import json
from pathlib import Path

from quadcosim.scenarios.output_options import free_file

from quadcosim.infra.errors import UsageError, refusals
from quadcosim.infra.files import figure_file, printable, save_figure
from quadcosim.infra.inputs import read_small_text

RESULTS_FILE = "results.npz"
#: Width and height (inches) of one signal's axes.
AXES_SIZE = (9.0, 2.6)


def load(run) -> tuple:
    """The result of a finished run and its folder.

    Parameters
    ----------
    run : str or pathlib.Path
        The run's folder, its ``results.npz``, or its streamed record (``--stream``).

    Returns
    -------
    result : quadcosim.orchestrator.Result
    folder : pathlib.Path

    Raises
    ------
    ValueError
        No record there (the message says what a run folder holds), a damaged record (named,
        with what is wrong), or a record of no sample.
    """
    import zipfile

    from quadcosim.orchestrator import Result

    path = Path(run)
    folder = path if path.is_dir() else path.parent
    if not path.exists() or (path.is_dir() and not _holds_record(path)):
        raise ValueError(f"{run}: no {RESULTS_FILE} or streamed record there; give the folder of a finished run "
                         "(the --out of `quadcosim run`, e.g. results/tp) or its results.npz")
    try:
        result = Result.load(path)
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile) as error:
        raise ValueError(f"{run}: the run's record is damaged and cannot be read ({type(error).__name__}: {error}); "
                         "run the scenario again") from None
    if len(result) == 0:
        raise ValueError(f"{run}: the run's record holds no sample (it stopped before its loop; see its "
                         "metrics.json): nothing to draw")
    return result, folder


def _holds_record(folder: Path) -> bool:
    from quadcosim.orchestrator.result import FOLDER

    return (folder / RESULTS_FILE).exists() or (folder / FOLDER).is_dir() or (folder / "meta.json").exists()


def _check(result, folder: Path, signal: str):
    """Refuse a signal the run did not record, naming the nearest and, for a signal the scenario
    left out of its files, the option that records it."""
    try:
        result.columns(signal)
    except KeyError as error:
        hint = ""
        try:
            left_out = json.loads(read_small_text(folder / "metrics.json", "the run's metrics.json",
                                                  "")).get("signals_not_saved", [])
        except (OSError, ValueError, AttributeError):
            left_out = []
        if any(name == signal or name.startswith(signal + "_") for name in left_out):
            hint = f" The scenario left {signal} out of its files (it follows from others): run it with --record all."
        raise ValueError(f"{folder}: {error.args[0]}{hint}") from None


def _label(folder: Path) -> str:
    return folder.name or str(folder)


#: Where ``quadcosim compare`` writes its figure when no ``--out`` is given.
COMPARE_FOLDER = Path("results")


def _run_labels(folders) -> list[str]:
    """Each run's name in a legend: its folder's name, or its path where two names are alike
    (``a/tp`` and ``b/tp``)."""
    names = [_label(folder) for folder in folders]
    return [str(folder) if names.count(name) > 1 else name for folder, name in zip(folders, names, strict=True)]


#: Figure formats of ``--format``: the file's suffix.
FORMATS = ("png", "svg", "pdf")


def signal_lines(run) -> list[str]:
    """The signals a finished run recorded, as ``quadcosim plot RUN`` lists them: each vector
    once (its components in brackets), then the scalar signals, each with its unit.

    Parameters
    ----------
    run : str or pathlib.Path
        The run's folder or its ``results.npz``.

    Returns
    -------
    list of str
        A heading, then one line per vector or signal: ``IMU.acc [x, y, z] (m/s2)``.
    """
    from quadcosim.orchestrator.signals import vector_groups

    result, folder = load(run)
    units = result.meta.get("units", {})
    vectors = vector_groups(result.names)
    in_vector = {name for members in vectors.values() for name in members}

    def unit(members):
        found = {units.get(m) or "unit unknown" for m in members}
        return found.pop() if len(found) == 1 else "mixed units"

    span = result.time[-1] - result.time[0]
    lines = [f"{folder}: {len(result.names)} signals, {len(result)} samples over {span:g} s "
             "(plot a vector by its name, or any component):"]
    for vector, members in vectors.items():
        tails = ", ".join(m.rsplit(".", 1)[1][len(vector.rsplit(".", 1)[1]):].lstrip("_") for m in members)
        lines.append(f"  {vector} [{tails}] ({unit(members)})")
    for name in result.names:
        if name not in in_vector:
            lines.append(f"  {name} ({unit([name])})")
    return lines


def _degrees(unit: str | None) -> str | None:
    """The unit in degrees of an angle or angular rate unit (``rad/s`` -> ``deg/s``), else None."""
    if unit == "rad" or (unit or "").startswith("rad/"):
        return "deg" + unit[3:]
    return None


def _draw(ax, result, signal: str, deg: bool, label_prefix: str = ""):
    """``signal`` of ``result`` on ``ax``: its name as the axes' title, its unit as the y label
    (a label that always fits the axes' height), in degrees with ``deg`` when it is an angle."""
    units = result.meta.get("units", {})
    found = {units.get(m) or None for m in result.columns(signal)}
    unit = found.pop() if len(found) == 1 else None
    in_degrees = _degrees(unit) if deg else None
    if in_degrees:
        result.plot(signal, ax=ax, scale=180.0 / 3.141592653589793, unit=in_degrees, label_prefix=label_prefix)
    else:
        result.plot(signal, ax=ax, label_prefix=label_prefix)
    ax.set_ylabel(in_degrees or unit or "unit unknown")
    ax.set_title(printable(signal), loc="left", fontsize=9)


def _with_format(out, figure_format: str | None):
    """The ``--out`` given, made to agree with ``--format``: a file without a figure suffix takes
    the format's, a folder is kept (the default name carries the format), another figure suffix
    is refused."""
    if not out or not figure_format or Path(out).is_dir():
        return out
    path = Path(out)
    suffix = path.suffix.lstrip(".").lower()
    if suffix == figure_format:
        return path
    if suffix in FORMATS:
        raise ValueError(f"--out {out} and --format {figure_format} disagree: give one of them")
    return path.with_name(f"{path.name}.{figure_format}")


def plot(run, signals, out=None, deg: bool = False, figure_format: str | None = None,
         tracking: bool = False, overwrite: bool = False) -> Path:
    """One figure of a finished run: each signal (or vector) on its own axes, against time; with
    ``tracking``, the signals together on one axes (per component), a setpoint and its response.

    Parameters
    ----------
    run : str or pathlib.Path
        The run's folder or its ``results.npz``.
    signals : sequence of str
        Signal or vector names.
    out : str or pathlib.Path, optional
        PNG, SVG or PDF file, replaced if it is there (asked for). By default
        ``plot-<first signal>.png`` in the run's folder, or with a figure there (and no
        ``overwrite``) the next free ``plot-<first signal>-N.png``, said on standard error.
    deg : bool
        Draw angles (rad) and angular rates (rad/s, rad/s2) in degrees; other signals as they are.
    figure_format : {"png", "svg", "pdf"}, optional
        The file's format when ``out`` has no suffix or is not given (default png).
    tracking : bool
        Draw the signals on shared axes: the k-th component of each on the k-th axes
        (``Setpoint.theta_d`` and ``Quadrotor.theta``: roll, pitch and yaw, setpoint against
        response). The signals must have as many components and one unit.
    overwrite : bool
        Replace the default file rather than take the next free name.

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    ValueError
        A signal the run did not record; with ``tracking``, fewer than two signals, or signals of
        different sizes or units (named).
    """
    import matplotlib.pyplot as plt

    if tracking and len(signals) < 2:
        raise ValueError("--tracking draws two signals or more on one axes (a setpoint and its response: "
                         "Setpoint.theta_d Quadrotor.theta); give at least two")
    name = f"{'tracking' if tracking else 'plot'}-{signals[0]}.{figure_format or 'png'}"
    # a path given is checked before the run is read
    path = figure_file(_with_format(out, figure_format), name, None) if out else None
    result, folder = load(run)
    if path is None:
        path = figure_file(None, name, folder)
        path = path if overwrite else free_file(path, "plot")
    for signal in signals:
        _check(result, folder, signal)
    if tracking:
        return _tracking(result, folder, signals, path, deg)
    fig, axes = plt.subplots(len(signals), 1, sharex=True, squeeze=False, layout="constrained",
                             figsize=(AXES_SIZE[0], AXES_SIZE[1] * len(signals)))
    for ax, signal in zip(axes[:, 0], signals, strict=True):
        _draw(ax, result, signal, deg)
    for ax in axes[:-1, 0]:
        ax.set_xlabel("")
    fig.suptitle(printable(_label(folder)), fontsize=10)
    try:
        return save_figure(fig, path, dpi=120)
    finally:
        plt.close(fig)


def _tracking(result, folder: Path, signals, path: Path, deg: bool) -> Path:
    """:func:`plot`'s ``tracking`` view: the k-th component of every signal on the k-th axes."""
    import matplotlib.pyplot as plt

    columns = [result.columns(signal) for signal in signals]
    sizes = {len(c) for c in columns}
    if len(sizes) > 1:
        told = ", ".join(f"{s} ({len(c)})" for s, c in zip(signals, columns, strict=True))
        raise ValueError(f"--tracking draws component against component: the signals differ in size ({told}); "
                         "give vectors of one size, or single components (Setpoint.theta_d2 Quadrotor.theta2)")
    units = result.meta.get("units", {})
    found = {units.get(m) or None for c in columns for m in c}
    if len(found) > 1:
        told = ", ".join(f"{s} ({units.get(c[0]) or 'unit unknown'})" for s, c in zip(signals, columns, strict=True))
        raise ValueError(f"--tracking draws the signals on one y axis: their units differ ({told})")
    fig, axes = plt.subplots(sizes.pop(), 1, sharex=True, squeeze=False, layout="constrained",
                             figsize=(AXES_SIZE[0], AXES_SIZE[1] * len(columns[0])))
    for k, ax in enumerate(axes[:, 0]):
        for j, component in enumerate(c[k] for c in columns):
            _draw(ax, result, component, deg)
            ax.lines[-1].set_linestyle("--" if j == 0 else "-")  # the first (the setpoint) dashed
        ax.set_title(printable(" vs ".join(c[k] for c in columns)), loc="left", fontsize=9)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1), fontsize=8)
    for ax in axes[:-1, 0]:
        ax.set_xlabel("")
    fig.suptitle(printable(f"{_label(folder)}: {' and '.join(signals)}"), fontsize=10)
    try:
        return save_figure(fig, path, dpi=120)
    finally:
        plt.close(fig)


def compare(runs, signal: str, out=None, deg: bool = False, figure_format: str | None = None,
            overwrite: bool = False) -> Path:
    """One signal of several finished runs on one figure, one curve per run (per component for a
    vector, on its own axes).

    Parameters
    ----------
    runs : sequence of str or pathlib.Path
        Two or more run folders (or their ``results.npz``).
    signal : str
        Signal or vector name, recorded by every run.
    out : str or pathlib.Path, optional
        PNG, SVG or PDF file, replaced if it is there (asked for). By default
        ``results/compare-<signal>.png``, or with a figure there (and no ``overwrite``) the next
        free ``results/compare-<signal>-N.png``, said on standard error.
    deg : bool
        Draw an angle (rad) or angular rate (rad/s) in degrees.
    figure_format : {"png", "svg", "pdf"}, optional
        The file's format when ``out`` has no suffix or is not given (default png).
    overwrite : bool
        Replace the default file rather than take the next free name.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    import matplotlib.pyplot as plt

    name = f"compare-{signal}.{figure_format or 'png'}"
    if out:
        path = figure_file(_with_format(out, figure_format), name, None)
    else:
        path = figure_file(None, name, COMPARE_FOLDER)
        path = path if overwrite else free_file(path, "compare")
    loaded = [load(run) for run in runs]
    for result, folder in loaded:
        _check(result, folder, signal)
    labels = _run_labels([folder for _, folder in loaded])
    components = loaded[0][0].columns(signal)
    fig, axes = plt.subplots(len(components), 1, sharex=True, squeeze=False, layout="constrained",
                             figsize=(AXES_SIZE[0], AXES_SIZE[1] * len(components)))
    for ax, component in zip(axes[:, 0], components, strict=True):
        for (result, _), label in zip(loaded, labels, strict=True):
            if component in result.names:
                _draw(ax, result, component, deg)
                ax.lines[-1].set_label(printable(label))  # the component is the axes' title already
        ax.legend(fontsize=7, loc="best")
    for ax in axes[:-1, 0]:
        ax.set_xlabel("")
    fig.suptitle(printable(f"{signal}: {' vs '.join(labels)}"), fontsize=10)
    try:
        return save_figure(fig, path, dpi=120)
    finally:
        plt.close(fig)


def plot_command(args) -> int:
    """``quadcosim plot``: exit code 0; raises :class:`~quadcosim.infra.errors.UsageError` for a
    run or signal that is not there (exit 2), :class:`~quadcosim.infra.errors.RunError` for a full
    disk (exit 1).

    Parameters
    ----------
    args : argparse.Namespace
        ``run``, ``signals`` and ``out``, as :func:`add_arguments` declares them.
    """
    with refusals(usage=(ValueError,)):  # OutputRefused among them; a full disk: nothing left under its name
        if not args.signals:
            print("\n".join(signal_lines(args.run)))
            return 0
        print(plot(args.run, args.signals, args.out, deg=args.deg, figure_format=args.format,
                   tracking=args.tracking, overwrite=args.overwrite))
    return 0


def compare_command(args) -> int:
    """``quadcosim compare``: exit code 0; raises :class:`~quadcosim.infra.errors.UsageError` for
    a run or signal that is not there (exit 2), :class:`~quadcosim.infra.errors.RunError` for a
    full disk (exit 1).

    Parameters
    ----------
    args : argparse.Namespace
        ``items`` (the runs, then the signal unless ``signal`` is given), ``signal`` and ``out``,
        as :func:`add_arguments` declares them.
    """
    runs, signal = (args.items, args.signal) if args.signal else (args.items[:-1], args.items[-1])
    if len(runs) < 2:
        raise UsageError("give two runs or more, then the signal: compare RUN RUN SIGNAL")
    with refusals(usage=(ValueError,)):  # OutputRefused among them; a full disk: nothing left under its name
        print(compare(runs, signal, args.out, deg=args.deg, figure_format=args.format,
                      overwrite=args.overwrite))
    return 0


def add_arguments(sub):
    """The ``plot`` and ``compare`` sub-commands, added to the sub-parsers ``sub``."""
    plotting = sub.add_parser("plot", help="signals of a finished run against time (no signal: list them)")
    plotting.add_argument("run", help="the run's folder (its --out) or its results.npz")
    plotting.add_argument("signals", nargs="*", metavar="SIGNAL",
                          help="signal or vector names (IMU.acc); none: list the run's signals and their units")
    _add_figure_options(plotting, "RUN/plot-SIGNAL.png, or the next free -N name")
    plotting.add_argument("--overwrite", action="store_true",
                          help="replace RUN/plot-SIGNAL.png rather than take the next free name")
    plotting.add_argument("--tracking", action="store_true",
                          help="the signals on shared axes, component by component: a setpoint against its "
                               "response (plot RUN Setpoint.theta_d Quadrotor.theta --tracking --deg); the first "
                               "is dashed")
    plotting.set_defaults(func=plot_command)
    comparing = sub.add_parser("compare", help="one signal of several finished runs on one figure",
                               usage="quadcosim compare [-h] [--out FILE] [--overwrite] RUN RUN [RUN...] SIGNAL\n"
                                     "       quadcosim compare [-h] [--out FILE] [--overwrite] --signal SIGNAL RUN RUN "
                                     "[RUN...]")
    comparing.add_argument("items", nargs="+", metavar="RUN... SIGNAL",
                           help="two run folders or more (or their results.npz), then a signal or vector name")
    comparing.add_argument("--signal", help="the signal, when given apart: then every positional is a run")
    _add_figure_options(comparing, "results/compare-SIGNAL.png, or the next free -N name")
    comparing.add_argument("--overwrite", action="store_true",
                           help="replace results/compare-SIGNAL.png rather than take the next free name")
    comparing.set_defaults(func=compare_command)


def _add_figure_options(parser, default: str):
    parser.add_argument("--out", help=f"PNG, SVG or PDF file (default {default})")
    parser.add_argument("--format", choices=FORMATS, default=None,
                        help="figure format: png (120 dpi), svg or pdf (vector, for a report or a thesis); "
                             "default png, or the suffix of --out")
    parser.add_argument("--deg", action="store_true",
                        help="angles (rad) and angular rates (rad/s) in degrees; other signals as they are")
