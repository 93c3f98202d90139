"""A metric of a sweep table against one option, one curve per value of another.

Members that share the option values (Monte Carlo seeds, or options not shown) are pooled:
the curve is their mean, the band their spread (minimum to maximum), and each member is a
faint point. A member that diverged is never a value: it is drawn as a red cross on the top edge
of the axes at its option value, and counted in the legend. Failed members are left out and
counted in the title. Curves and categories are in numeric order (8, 16, 24, not 16, 24, 8).
"""

from __future__ import annotations

import math
from collections import defaultdict
from pathlib import Path

import numpy as np

from quadcosim.infra.files import save_figure


def _number(value) -> float | None:
    if isinstance(value, bool) or value is None:
        return None
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return number if math.isfinite(number) else None


def metric_unit(name: str) -> str:
    """The unit a metric's name ends with (``rms_error_deg[0]`` -> ``deg``); empty if none.

    Parameters
    ----------
    name : str
        A metric column of a sweep table.

    Returns
    -------
    str
        The unit, or ``""``.
    """
    from quadcosim.scenarios.metrics import unit_of_name

    return unit_of_name(name.split("[", 1)[0]) or ""


def _labelled(name: str, unit: str) -> str:
    return f"{name} ({unit})" if unit else name


def metric_label(metric: str, components: dict | None = None) -> str:
    """A metric as an axis names it: ``roll: rms_error_deg[0]`` when ``components`` says what
    its index is, else the column name.

    Parameters
    ----------
    metric : str
        A metric column (``rms_error_deg[0]``).
    components : dict, optional
        Column to the component it is (``{"rms_error_deg[0]": "roll"}``).

    Returns
    -------
    str
    """
    component = (components or {}).get(metric)
    return f"{component}: {metric}" if component else metric


def plot(columns: dict[str, list], metric: str, x: str, by: str | None = None, out=None, logy: bool = False,
         ax=None, units: dict | None = None, subtitle: str = "", components: dict | None = None):
    """Draw ``metric`` against option ``x``, grouped by option ``by``.

    Parameters
    ----------
    columns : dict
        A sweep table as columns (:func:`quadcosim.studies.sweep.read_table`).
    metric, x, by : str
        Column names: a metric, the option along the horizontal axis, the option that splits
        the members into curves (optional).
    out : path, optional
        File to save (PNG, SVG); the figure is returned when absent.
    logy : bool
        Logarithmic metric axis. The ``x`` axis is logarithmic by itself when ``x`` is positive
        and spans more than a decade.
    ax : matplotlib Axes, optional
        Draw into it instead of a new figure.
    units : dict, optional
        Unit of a column by name (the options'); a metric's unit is read from the end of its
        name (:func:`metric_unit`) unless given here.
    subtitle : str
        A second line of the title (e.g. the scenario and the options held fixed).
    components : dict, optional
        What the metric's index is (``{"rms_error_deg[0]": "roll"}``), named on the axis and in
        the title (:func:`metric_label`).

    Returns
    -------
    str or matplotlib.figure.Figure
        The saved path, or the figure.
    """
    import matplotlib.pyplot as plt

    groups, categories, numeric_x, failed, diverged = _groups(columns, metric, x, by)
    if ax is None:
        figure, ax = plt.subplots(figsize=(8, 5))
    else:
        figure = ax.figure
    units = units or {}
    by_unit = f" {units[by]}" if by and units.get(by) else ""
    for n, (key, series) in enumerate(sorted(groups.items(), key=lambda item: natural_key(item[0]))):
        _curve(ax, series, f"C{n % 10}", f"{by} = {key}{by_unit}" if by else metric, banded=not categories)
    if diverged:
        from matplotlib.transforms import blended_transform_factory

        ax.plot(diverged, [1.0] * len(diverged), "x", color="red", ms=9, mew=2, clip_on=False, zorder=5,
                transform=blended_transform_factory(ax.transData, ax.transAxes),
                label=f"diverged ({len(diverged)}): a crash, no value")
    xs = [a for series in groups.values() for a in series] + diverged
    if numeric_x and min(xs) > 0 and max(xs) / min(xs) > 10:
        from matplotlib.ticker import NullFormatter

        ax.set_xscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())  # labels at the decades only: never overlapping
    if logy:
        ax.set_yscale("log")
    if categories:
        ax.set_xticks(range(len(categories)), categories)
    ax.set_xlabel(_labelled(x, units.get(x, "")))
    named = metric_label(metric, components)
    ax.set_ylabel(_labelled(named, units.get(metric) or metric_unit(metric)))
    title = f"{named} against {x}" + (f", by {by}" if by else "")
    if failed:
        title += f" ({failed} failed member{'s' * (failed > 1)} not shown)"
    ax.set_title(title + (f"\n{subtitle}" if subtitle else ""), fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    if out is None:
        return figure
    path = Path(out)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.tight_layout()
    try:
        save_figure(figure, path, dpi=120)
    finally:
        plt.close(figure)
    return str(path)


def natural_key(value):
    """A sort key that puts numbers (and numeric text) in numeric order before other text:
    ``8, 16, 24``, never ``16, 24, 8``."""
    number = _number(value)
    return (0, number, "") if number is not None else (1, 0.0, str(value))


def _groups(columns, metric, x, by):
    """The finished members' metric by group and x position; the x categories (text options),
    whether x is numeric, how many members failed, and the x positions of those that diverged."""
    for name in (metric, x, by):
        if name is not None and name not in columns:
            from quadcosim.orchestrator.fmu import nearest

            raise KeyError(f"the sweep table has no column {name!r}.{nearest(name, columns)}")
    count = len(columns[x])
    status = columns.get("status", ["ok"] * count)
    kept = [i for i in range(count) if status[i] == "ok" and _number(columns[metric][i]) is not None]
    crashed = [i for i in range(count) if status[i] == "diverged"]
    failed = sum(s not in ("ok", "diverged") for s in status)
    if not kept and not crashed:
        raise ValueError(f"no finished member has a numeric {metric!r}")
    xs = [columns[x][i] for i in kept + crashed]
    numeric_x = all(_number(v) is not None for v in xs)
    categories = [] if numeric_x else sorted(set(map(_shown, xs)), key=natural_key)

    def position(i):
        return float(columns[x][i]) if numeric_x else float(categories.index(_shown(columns[x][i])))

    groups: dict[object, dict[float, list[float]]] = defaultdict(lambda: defaultdict(list))
    for i in kept:
        groups[columns[by][i] if by else None][position(i)].append(float(columns[metric][i]))
    return groups, categories, numeric_x, failed, sorted({position(i) for i in crashed})


def _shown(value) -> str:
    """A category as the command line writes it: on/off for a switch."""
    return ("on" if value else "off") if isinstance(value, bool) else str(value)


def _curve(ax, series: dict[float, list[float]], colour: str, label: str, banded: bool = True):
    """One group: the mean through its x positions; with pooled members, their spread (a band
    between numeric positions, a bar at each category) and points."""
    at = np.array(sorted(series))
    values = [np.array(series[a]) for a in at]
    pooled = max(len(v) for v in values)
    means = np.array([v.mean() for v in values])
    ax.plot(at, means, "o-" if banded else "o", color=colour,
            label=label + (f" (mean of {'' if min(map(len, values)) == pooled else 'up to '}{pooled})"
                           if pooled > 1 else ""))
    if pooled > 1:
        lows, highs = np.array([v.min() for v in values]), np.array([v.max() for v in values])
        if banded:
            ax.fill_between(at, lows, highs, color=colour, alpha=0.15)
        else:
            ax.errorbar(at, means, yerr=[means - lows, highs - means], fmt="none", ecolor=colour, capsize=6,
                        alpha=0.6)
        for a, v in zip(at, values, strict=True):
            ax.plot(np.full(len(v), a), v, ".", color=colour, alpha=0.3, ms=3)
