"""What every scenario's figures share: titles that name the run, shaded fault windows, a
floor under the span of an axis, and units on every axis.

A figure of a quasi-stationary run must not stretch a 1e-14 deg wobble over the whole axis:
:func:`floor_span` widens any axis whose data span less than a stated minimum, about the
middle of the data. Faults come from ``result.meta["faults"]`` (target, kind, start, stop,
value), as :func:`quadcosim.scenarios.run` records them.
"""

from __future__ import annotations

import contextlib
import sys
import textwrap

import numpy as np

FAULT_COLOUR = "#d62728"


@contextlib.contextmanager
def closed_on_failure():
    """Close the figures opened inside the block if it raises (an error or an interrupt).

    A report that fails half-way would otherwise leave its figure open in pyplot, and in a
    process that runs many scenarios (a notebook, a sweep) those figures add up.
    """
    pyplot = sys.modules.get("matplotlib.pyplot")
    before = set(pyplot.get_fignums()) if pyplot else set()
    try:
        yield
    except BaseException:
        pyplot = sys.modules.get("matplotlib.pyplot")  # the block may have imported it
        if pyplot:
            for number in set(pyplot.get_fignums()) - before:
                pyplot.close(number)
        raise


def faults_of(result) -> list[dict]:
    """The faults injected in the run of ``result``, as dicts (target, kind, start, stop, value).

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        A run's record.

    Returns
    -------
    list of dict
        ``start`` and ``stop`` in s, ``value`` in the faulted signal's unit (None for a stuck
        fault holding its first value, or a dropout); empty when no fault was injected.
    """
    return [dict(f) for f in result.meta.get("faults", []) or []]


def fault_text(faults: list[dict], units: dict | None = None) -> str:
    """One line per fault: ``offset +0.1 rad/s on IMU.omega_x, 2-3 s``.

    Parameters
    ----------
    faults : list of dict
        As :func:`faults_of` gives them.
    units : dict, optional
        Unit of each faulted input (``"IMU.omega_x" -> "rad/s"``), printed after the value.

    Returns
    -------
    str
        Empty when there is no fault.
    """
    lines = []
    for f in faults:
        unit = (units or {}).get(f["target"], "")
        value = f.get("value")
        if f["kind"] == "offset":
            what = f"offset {value:+g}{' ' + unit if unit else ''}"
        elif f["kind"] == "scale":
            what = f"scale x{value:g}"
        elif f["kind"] == "stuck":
            what = "stuck" + (f" at {value:g}{' ' + unit if unit else ''}" if value is not None else "")
        elif f["kind"] == "noise":
            what = f"noise sd {value:g}{' ' + unit if unit else ''}"
        else:
            what = f["kind"]
        lines.append(f"fault: {what} on {f['target']}, {f['start']:g}-{f['stop']:g} s")
    return "\n".join(lines)


def shade_faults(axes, faults: list[dict], label: bool = True) -> None:
    """Shade each fault's window on every axis of ``axes``; the first axis' legend names them.

    Parameters
    ----------
    axes : sequence of matplotlib.axes.Axes
        Axes whose x axis is time (s).
    faults : list of dict
        As :func:`faults_of` gives them.
    label : bool
        Put "fault window" in the first axis' legend.
    """
    for k, ax in enumerate(axes):
        for n, f in enumerate(faults):
            ax.axvspan(f["start"], f["stop"], color=FAULT_COLOUR, alpha=0.12, lw=0,
                       label="fault window" if label and k == 0 and n == 0 else None)


def floor_span(ax, minimum: float) -> None:
    """Widen the y axis to span at least ``minimum`` (in the axis' unit), about the middle of
    what it shows, and print plain tick values (no offset such as ``1e-14 + ...``).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axis, drawn.
    minimum : float
        Smallest span of the y axis (its unit), > 0.
    """
    low, high = ax.get_ylim()
    if high - low < minimum:
        middle = 0.5 * (low + high)
        ax.set_ylim(middle - 0.5 * minimum, middle + 0.5 * minimum)
    ax.ticklabel_format(axis="y", useOffset=False, style="plain")


def title_lines(*parts: str, width: int = 110) -> str:
    """Join the non-empty ``parts`` into a title, each wrapped at ``width`` characters.

    Parameters
    ----------
    *parts : str
        Lines of the title (may be empty or hold several lines).
    width : int
        Characters per line.

    Returns
    -------
    str
        The title.
    """
    lines = []
    for part in parts:
        for line in part.splitlines():
            lines.extend(textwrap.wrap(line, width) or [""])
    return "\n".join(line for line in lines if line)


def label_axes(axes) -> None:
    """Refuse an axis without a y label and the last without an x label (units are part of
    the label, in brackets or parentheses): raised before a figure is saved.

    Parameters
    ----------
    axes : sequence of matplotlib.axes.Axes

    Raises
    ------
    ValueError
        An axis has no label.
    """
    for ax in axes:
        if not ax.get_ylabel():
            raise ValueError(f"an axis of figure {ax.figure.get_suptitle()!r} has no y label")
    if not axes[-1].get_xlabel():
        raise ValueError(f"the bottom axis of figure {axes[-1].figure.get_suptitle()!r} has no x label")


#: Degrees of a jump between two samples of a wrapped angle that is a wrap, not a motion.
WRAP_JUMP_DEG = 180.0


def angle_curve(t, degrees, points: int = 2000):
    """A curve of an angle wrapped to (-180, 180] deg, as drawn: reduced to its envelope, with a
    gap (NaN) where it wraps, so that the plot shows no vertical line at +-180 deg.

    The angle is unwrapped before the envelope (a run of samples across the wrap keeps its
    true extremes) and wrapped again after it.

    Parameters
    ----------
    t : ndarray
        Times (s).
    degrees : ndarray
        The angle (deg), wrapped or not.
    points : int
        Runs of the envelope (:func:`quadcosim.orchestrator.result.envelope`).

    Returns
    -------
    times, values : ndarray
        Ready for ``ax.plot``.
    """
    from quadcosim.orchestrator.result import envelope

    unwrapped = np.degrees(np.unwrap(np.radians(degrees)))
    return wrapped_curve(*envelope(t, unwrapped, points))


def wrapped_curve(times, values):
    """An unwrapped angle's envelope (deg) wrapped to (-180, 180] deg, with a gap (NaN) where it
    wraps (see :func:`angle_curve`).

    Parameters
    ----------
    times : ndarray
        Times (s).
    values : ndarray
        The unwrapped angle (deg) at those times.

    Returns
    -------
    times, values : ndarray
        Ready for ``ax.plot``.
    """
    wrapped = (values + 180.0) % 360.0 - 180.0
    breaks = np.flatnonzero(np.abs(np.diff(wrapped)) > WRAP_JUMP_DEG) + 1
    return np.insert(times.astype(float), breaks, np.nan), np.insert(wrapped, breaks, np.nan)
