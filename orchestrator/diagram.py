"""A picture of the wiring, drawn from the system itself (PNG or SVG, by file suffix).

Blocks stand in columns by their place in the dependency order; each arrow is one group of
connections between two blocks, labelled with the signals it carries (vector components
folded: ``acc_x, acc_y, acc_z`` reads ``acc[xyz]``). Feedback arrows, to a block earlier in
the order, are drawn dashed below. FMU blocks are shaded.
"""

from __future__ import annotations

import re
from collections import defaultdict
from pathlib import Path

from orchestrator.blocks import Constant, FMUBlock


def fold(names: list[str]) -> str:
    """Fold vector components into one label.

    Parameters
    ----------
    names : list of str
        Signal names.

    Returns
    -------
    str
        ``[omega_r1, omega_r2, omega_r3, omega_r4]`` gives ``omega_r[1-4]``; ``acc_x, acc_y,
        acc_z`` gives ``acc[xyz]``.
    """
    groups: dict[str, list[str]] = defaultdict(list)
    order = []
    for name in names:
        match = re.fullmatch(r"(.*?)(_?)([xyz]|\d+)", name)
        stem = (match.group(1) + match.group(2)) if match else name
        if stem not in groups:
            order.append(stem)
        groups[stem].append(match.group(3) if match else "")
    parts = []
    for stem in order:
        suffixes = groups[stem]
        if len(suffixes) == 1:
            parts.append(stem + suffixes[0])
        elif all(s.isdigit() for s in suffixes):
            parts.append(f"{stem}[{suffixes[0]}-{suffixes[-1]}]")
        else:
            parts.append(f"{stem}[{''.join(suffixes)}]")
    return ", ".join(parts)


def draw(system, path) -> Path:
    """Draw the wiring of ``system`` into ``path`` (PNG or SVG, by suffix).

    Parameters
    ----------
    system : orchestrator.System
        The system; it need not be fully connected.
    path : str or pathlib.Path
        Output file; its folder is created.

    Returns
    -------
    pathlib.Path
        ``path``. Constant blocks made by :meth:`System.set_input` are drawn as a note
        ``value → inputs`` above the block they feed.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    order, links, constants = _wiring(system)
    fig, ax = plt.subplots(figsize=(max(8, 3.4 * len(order)), 4.5))
    centres = _draw_blocks(ax, order, constants)
    position = {b.name: i for i, b in enumerate(order)}
    for k, ((src, dst), names) in enumerate(sorted(links.items(), key=lambda item: position[item[0][0]])):
        _draw_link(ax, centres[src], centres[dst], position[dst] - position[src], k, names)
    fig.set_figheight(4.5 + 0.25 * len(order))
    span = COLUMN * max(len(order) - 1, 1) * ARC / 2  # height of the longest possible arc
    ax.set_xlim(-0.6, COLUMN * len(order))
    ax.set_ylim(-HEIGHT / 2 - span - 0.3, HEIGHT / 2 + span + 0.6)
    ax.axis("off")
    ax.set_title(f"{len(order)} blocks, {len(system.connections)} connections, macro step {system.dt * 1e3:g} ms")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with matplotlib.rc_context({"svg.fonttype": "none"}):  # SVG text stays text
        fig.savefig(path, dpi=130, bbox_inches="tight")
    plt.close(fig)
    return path


# Layout, in axis units: a block's box, the spacing of the columns; the bend of the arcs
# (the height of an arc is ARC / 2 times its length).
WIDTH, HEIGHT, COLUMN, ARC = 2.2, 1.0, 3.8, 0.3


def _wiring(system):
    """Blocks to draw in order; connections grouped by (source, destination) block; and the
    constant ties-off as ``{block: {value: [inputs]}}``."""
    ties = {b.name: b for b in system.blocks.values() if isinstance(b, Constant) and b.ties}
    order = [b for b in system.order() if b.name not in ties]
    links: dict[tuple[str, str], list[str]] = defaultdict(list)
    constants: dict[str, dict[float, list[str]]] = defaultdict(lambda: defaultdict(list))
    for dst, src in system.connections.items():
        src_block, src_name = src.split(".", 1)
        dst_block, dst_name = dst.split(".", 1)
        if src_block in ties:
            tie = ties[src_block]
            constants[dst_block][float(tie.values[tie.outputs.index(src_name)])].append(dst_name)
            continue
        links[(src_block, dst_block)].append(src_name if src_name == dst_name else f"{src_name}→{dst_name}")
    return order, links, constants


def _draw_blocks(ax, order, constants) -> dict[str, tuple[float, float]]:
    from matplotlib.patches import FancyBboxPatch

    centres = {}
    for column, block in enumerate(order):
        x = column * COLUMN
        centres[block.name] = (x + WIDTH / 2, 0.0)
        shade = "#dbe8f5" if isinstance(block, FMUBlock) else "#f3f3f3"
        ax.add_patch(FancyBboxPatch((x, -HEIGHT / 2), WIDTH, HEIGHT, boxstyle="round,pad=0.05",
                                    facecolor=shade, edgecolor="#333333"))
        kind = f"FMU {block.model}" if isinstance(block, FMUBlock) else type(block).__name__
        rate = f", every {block.period} steps" if block.period > 1 else ""
        ax.text(x + WIDTH / 2, 0.12, block.name, ha="center", va="center", fontsize=10, weight="bold")
        ax.text(x + WIDTH / 2, -0.2, kind + rate, ha="center", va="center", fontsize=7)
        if constants.get(block.name):
            note = "; ".join(f"{value:g} → {fold(names)}" for value, names in constants[block.name].items())
            ax.text(x + WIDTH / 2, HEIGHT / 2 + 0.15, note, ha="center", fontsize=6, color="#777777")
    return centres


def _draw_link(ax, source, destination, columns: int, k: int, names: list[str]):
    """An arrow ``columns`` columns ahead (negative: feedback, dashed, below the blocks)."""
    (x0, _), (x1, _) = source, destination
    forward = columns > 0
    if columns == 1:
        start, end, rad, label_y = (x0 + WIDTH / 2, 0.0), (x1 - WIDTH / 2, 0.0), 0.0, 0.08
    elif forward:  # over the blocks in between; the label at the top of the arc
        start, end, rad = (x0 + 0.3, HEIGHT / 2), (x1 - 0.3, HEIGHT / 2), -ARC
        label_y = HEIGHT / 2 + ARC * (end[0] - start[0]) / 2 - 0.05
    else:  # feedback, under the blocks; the label just inside the bottom of the arc
        start, end, rad = (x0, -HEIGHT / 2), (x1, -HEIGHT / 2), -ARC
        label_y = -HEIGHT / 2 - ARC * (start[0] - end[0]) / 2 + 0.1 + 0.25 * (k % 3)
    colour = "#1f4e79" if forward else "#a33"
    ax.annotate("", xy=end, xytext=start, arrowprops=dict(
        arrowstyle="-|>", color=colour, lw=1.2, linestyle="-" if forward else "--",
        connectionstyle=f"arc3,rad={rad}"))
    ax.text((start[0] + end[0]) / 2, label_y, fold(names).replace(", ", "\n"), ha="center",
            va="top" if columns > 1 else "bottom", fontsize=6, color=colour)
