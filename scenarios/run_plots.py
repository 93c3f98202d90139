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

from orchestrator.files import figure_file, printable, save_figure

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
    result : orchestrator.Result
    folder : pathlib.Path

    Raises
    ------
    ValueError
        No record there (the message says what a run folder holds), a damaged record (named,
        with what is wrong), or a record of no sample.
    """
    import zipfile

    from orchestrator import Result

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
    from orchestrator.stream import FOLDER

    return (folder / RESULTS_FILE).exists() or (folder / FOLDER).is_dir() or (folder / "meta.json").exists()


def _check(result, folder: Path, signal: str):
    """Refuse a signal the run did not record, naming the nearest and, for a signal the scenario
    left out of its files, the option that records it."""
    try:
        result.columns(signal)
    except KeyError as error:
        hint = ""
        try:
            left_out = json.loads((folder / "metrics.json").read_text()).get("signals_not_saved", [])
        except (OSError, ValueError):
            left_out = []
        if any(name == signal or name.startswith(signal + "_") for name in left_out):
            hint = f" The scenario left {signal} out of its files (it follows from others): run it with --record all."
        raise ValueError(f"{folder}: {error.args[0]}{hint}") from None


def _label(folder: Path) -> str:
    return folder.name or str(folder)


def plot(run, signals, out=None) -> Path:
    """One figure of a finished run: each signal (or vector) on its own axes, against time.

    Parameters
    ----------
    run : str or pathlib.Path
        The run's folder or its ``results.npz``.
    signals : sequence of str
        Signal or vector names.
    out : str or pathlib.Path, optional
        PNG, SVG or PDF file; ``plot-<first signal>.png`` in the run's folder by default.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    import matplotlib.pyplot as plt

    name = f"plot-{signals[0]}.png"
    path = figure_file(out, name, None) if out else None  # a path given is checked before the run is read
    result, folder = load(run)
    path = path or figure_file(None, name, folder)
    for signal in signals:
        _check(result, folder, signal)
    fig, axes = plt.subplots(len(signals), 1, sharex=True, squeeze=False, layout="constrained",
                             figsize=(AXES_SIZE[0], AXES_SIZE[1] * len(signals)))
    for ax, signal in zip(axes[:, 0], signals, strict=True):
        result.plot(signal, ax=ax)
    for ax in axes[:-1, 0]:
        ax.set_xlabel("")
    fig.suptitle(printable(f"{_label(folder)}: {', '.join(signals)}"), fontsize=10)
    try:
        return save_figure(fig, path, dpi=120)
    finally:
        plt.close(fig)


def compare(runs, signal: str, out=None) -> Path:
    """One signal of several finished runs on one figure, one curve per run (per component for a
    vector, on its own axes).

    Parameters
    ----------
    runs : sequence of str or pathlib.Path
        Two or more run folders (or their ``results.npz``).
    signal : str
        Signal or vector name, recorded by every run.
    out : str or pathlib.Path, optional
        PNG, SVG or PDF file; ``compare-<signal>.png`` in the current folder by default.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    import matplotlib.pyplot as plt

    path = figure_file(out, f"compare-{signal}.png", Path("."))
    loaded = [load(run) for run in runs]
    for result, folder in loaded:
        _check(result, folder, signal)
    components = loaded[0][0].columns(signal)
    fig, axes = plt.subplots(len(components), 1, sharex=True, squeeze=False, layout="constrained",
                             figsize=(AXES_SIZE[0], AXES_SIZE[1] * len(components)))
    for ax, component in zip(axes[:, 0], components, strict=True):
        for result, folder in loaded:
            if component in result.names:
                result.plot(component, ax=ax, label_prefix=f"{_label(folder)}: ")
    for ax in axes[:-1, 0]:
        ax.set_xlabel("")
    fig.suptitle(printable(f"{signal}: {' vs '.join(_label(folder) for _, folder in loaded)}"), fontsize=10)
    try:
        return save_figure(fig, path, dpi=120)
    finally:
        plt.close(fig)


def plot_command(args) -> int:
    """``quadcosim plot``: exit code 0, or 2 for a run or signal that is not there.

    Parameters
    ----------
    args : argparse.Namespace
        ``run``, ``signals`` and ``out``, as :func:`add_arguments` declares them.
    """
    import sys

    try:
        print(plot(args.run, args.signals, args.out))
    except ValueError as error:  # OutputRefused among them
        print(f"quadcosim plot: {error}", file=sys.stderr)
        return 2
    except OSError as error:  # a full disk (named; nothing left under the figure's name)
        print(f"quadcosim plot: failed: {error}", file=sys.stderr)
        return 1
    return 0


def compare_command(args) -> int:
    """``quadcosim compare``: exit code 0, or 2 for a run or signal that is not there.

    Parameters
    ----------
    args : argparse.Namespace
        ``items`` (the runs, then the signal unless ``signal`` is given), ``signal`` and ``out``,
        as :func:`add_arguments` declares them.
    """
    import sys

    runs, signal = (args.items, args.signal) if args.signal else (args.items[:-1], args.items[-1])
    if len(runs) < 2:
        print("quadcosim compare: give two runs or more, then the signal: compare RUN RUN SIGNAL", file=sys.stderr)
        return 2
    try:
        print(compare(runs, signal, args.out))
    except ValueError as error:  # OutputRefused among them
        print(f"quadcosim compare: {error}", file=sys.stderr)
        return 2
    except OSError as error:  # a full disk (named; nothing left under the figure's name)
        print(f"quadcosim compare: failed: {error}", file=sys.stderr)
        return 1
    return 0


def add_arguments(sub):
    """The ``plot`` and ``compare`` sub-commands, added to the sub-parsers ``sub``."""
    plotting = sub.add_parser("plot", help="signals of a finished run against time")
    plotting.add_argument("run", help="the run's folder (its --out) or its results.npz")
    plotting.add_argument("signals", nargs="+", metavar="SIGNAL", help="signal or vector names (IMU.acc)")
    plotting.add_argument("--out", help="PNG/SVG/PDF file (default RUN/plot-SIGNAL.png)")
    plotting.set_defaults(func=plot_command)
    comparing = sub.add_parser("compare", help="one signal of several finished runs on one figure",
                               usage="quadcosim compare [-h] [--out FILE] RUN RUN [RUN...] SIGNAL\n"
                                     "       quadcosim compare [-h] [--out FILE] --signal SIGNAL RUN RUN [RUN...]")
    comparing.add_argument("items", nargs="+", metavar="RUN... SIGNAL",
                           help="two run folders or more (or their results.npz), then a signal or vector name")
    comparing.add_argument("--signal", help="the signal, when given apart: then every positional is a run")
    comparing.add_argument("--out", help="PNG/SVG/PDF file (default compare-SIGNAL.png here)")
    comparing.set_defaults(func=compare_command)
