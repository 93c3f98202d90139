"""A picture of the wiring, drawn from the system itself (PNG or SVG, by file suffix).

The blocks stand in one row in the order the signals flow, from the sources (a setpoint)
onwards, as a Simulink diagram of the loop reads: for the lab's loop, Setpoint, Controller,
MotorMagnetics, Quadrotor, IMU, Quaternion_estim. Each arrow is one group of connections
between two blocks, labelled with the signals it carries (vector components folded:
``acc_x, acc_y, acc_z`` reads ``acc[xyz]``). An arrow to the next block is straight, its label
above it; an arrow that skips blocks runs above the row, and an arrow back against the flow
(a feedback) runs dashed below it, each on a lane of its own with its label just above its
horizontal run. FMU blocks are shaded; inputs held at a constant are noted inside their block.
"""

from __future__ import annotations

import re
from collections import defaultdict
from dataclasses import dataclass
from functools import partial
from pathlib import Path

from quadcosim.orchestrator.blocks import Constant, FMUBlock

from quadcosim.infra.files import atomic_path, save_figure

# Layout, in axis units (one unit is INCH inches on the page): a block's box, the spacing of the
# columns, the spacing of the lanes above and below the row.
WIDTH, COLUMN, LANE, INCH = 2.4, 4.0, 0.42, 0.62
FONT = 7  # pt, arrow labels
LINE = FONT / 72 * 1.25 / INCH  # height of a line of label text, axis units
CHAR = FONT / 72 * 0.6 / INCH  # width of a character of label text (a generous average), axis units
FORWARD, FEEDBACK = "#1f4e79", "#a33"


def fold(names: list[str]) -> str:
    """Fold vector components into one label.

    Parameters
    ----------
    names : list of str
        Signal names; ``"a→b"`` for a source ``a`` feeding an input of another name ``b``.

    Returns
    -------
    str
        ``[omega_r1, omega_r2, omega_r3, omega_r4]`` gives ``omega_r[1-4]``; ``acc_x, acc_y,
        acc_z`` gives ``acc[xyz]``; ``q_est0→q0 ... q_est3→q3`` gives ``q_est[0-3]→q[0-3]``.
    """
    groups: dict[tuple[str, str], list[str]] = defaultdict(list)
    for name in names:
        source, _, destination = name.partition("→")
        (stem, suffix), (stem_to, suffix_to) = _split(source), _split(destination or source)
        if suffix != suffix_to:  # components that do not correspond: no folding
            stem, stem_to, suffix = source, destination or source, ""
        groups[(stem, stem_to)].append(suffix)
    parts = []
    for (stem, stem_to), suffixes in groups.items():
        if len(suffixes) == 1:
            tail = suffixes[0]
        else:  # acc_x, acc_y, acc_z: acc[xyz]
            stem, stem_to = stem.rstrip("_"), stem_to.rstrip("_")
            tail = f"[{suffixes[0]}-{suffixes[-1]}]" if all(s.isdigit() for s in suffixes) else f"[{''.join(suffixes)}]"
        parts.append(stem + tail if stem == stem_to else f"{stem}{tail}→{stem_to}{tail}")
    return ", ".join(parts)


def _split(name: str) -> tuple[str, str]:
    """``"acc_x"`` -> ``("acc_", "x")``, ``"q0"`` -> ``("q", "0")``, ``"hold"`` -> ``("hold", "")``."""
    match = re.fullmatch(r"(.*?_?)([xyz]|\d+)", name)
    return (match.group(1), match.group(2)) if match and match.group(1) else (name, "")


@dataclass
class Arrow:
    """One group of connections, as drawn.

    Parameters
    ----------
    source, destination : str
        The blocks it joins.
    label : str
        The signals it carries, folded (:func:`fold`).
    side : int
        0: a straight arrow to the next block; +1: a run above the row (it skips blocks);
        -1: a dashed run below the row (a feedback, against the flow).
    lane : int
        The lane of its horizontal run, 0 nearest the row.
    x0, x1 : float
        Where it leaves its source and enters its destination (axis units).
    label_x : float
        Centre of its label on the horizontal run (axis units).
    box : float
        Height of the block boxes (axis units).
    """

    source: str
    destination: str
    label: str
    side: int = 0
    lane: int = 0
    x0: float = 0.0
    x1: float = 0.0
    label_x: float = 0.0
    box: float = 1.0

    @property
    def level(self) -> float:
        """Height of the horizontal run (axis units)."""
        return self.side * (self.box / 2 + LANE * (self.lane + 1))


def draw(system, path, title: str | None = None, cache: Path | None = None) -> Path:
    """Draw the wiring of ``system`` into ``path`` (PNG or SVG, by suffix).

    Parameters
    ----------
    system : quadcosim.orchestrator.System
        The system; it need not be fully connected.
    path : str or pathlib.Path
        Output file; its folder is created.
    title : str, optional
        First line of the title (e.g. the scenario and its key options); the second gives
        the counts of blocks and connections and the macro step.
    cache : pathlib.Path, optional
        Folder of drawings by :func:`wiring_key`: a wiring drawn before is copied from there
        rather than drawn again (matplotlib's drawing costs more CPU than a short run's
        loop); a new one is drawn and kept there. A cache that cannot be written is skipped.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    kept = cache / f"{wiring_key(system, title)}{path.suffix.lower()}" if cache is not None else None
    if kept is not None and kept.is_file():
        import shutil

        with atomic_path(path) as temporary:
            shutil.copyfile(kept, temporary)
        return path
    import matplotlib

    from quadcosim.infra.files import headless_backend

    headless_backend()
    import matplotlib.pyplot as plt

    fig = figure(system, title)
    try:
        with matplotlib.rc_context({"svg.fonttype": "none"}):  # SVG text stays text
            save_figure(fig, path, dpi=130, bbox_inches="tight", pad_inches=0.15)
    finally:
        plt.close(fig)
    if kept is not None:
        _keep(path, kept)
    return path


def wiring_key(system, title: str | None = None) -> str:
    """A digest of everything :func:`figure` draws of ``system`` (blocks, arrows, ties, faults,
    title) and of what draws it (this module's source, matplotlib's version): two systems of
    one key have one picture.

    Parameters
    ----------
    system : quadcosim.orchestrator.System
    title : str, optional
        The title's first line, as given to :func:`draw`.

    Returns
    -------
    str
        64 hexadecimal digits (SHA-256).
    """
    import hashlib
    from importlib.metadata import version

    order, links, constants = _wiring(system)
    blocks = [(name, isinstance(system.blocks[name], FMUBlock), _kind(system.blocks[name]),
               system.blocks[name].period) for name in order]
    faults = [(f.kind, f.target, f.start, f.stop) for f in system.faults]
    ties = [(b, list(v.items())) for b, v in constants.items()]  # in their order: it places what is drawn
    drawn = repr((title, blocks, list(links.items()), ties, list(system.connections.items()), blocks_text(system),
                  system.dt, faults, version("matplotlib")))
    digest = hashlib.sha256(Path(__file__).read_bytes())
    digest.update(drawn.encode())
    return digest.hexdigest()


def _keep(path: Path, kept: Path) -> None:
    """Copy the drawing ``path`` into the cache as ``kept``, whole or not at all; a cache that
    cannot be written (read-only, full) is left as it is."""
    import os
    import shutil
    import tempfile

    try:
        kept.parent.mkdir(parents=True, exist_ok=True)
        handle, name = tempfile.mkstemp(prefix=".", suffix=kept.suffix, dir=kept.parent)
        os.close(handle)
        try:
            shutil.copyfile(path, name)
            os.replace(name, kept)  # another process drawing the same wiring writes the same picture
        finally:
            Path(name).unlink(missing_ok=True)
    except OSError:
        pass


def _kind(block) -> str:
    """What a block's box says it is: its FMU's file name, or its Python class."""
    return f"FMU {Path(block.model).name}" if isinstance(block, FMUBlock) else type(block).__name__


def figure(system, title: str | None = None):
    """The wiring of ``system`` as a matplotlib figure (see :func:`draw`).

    Parameters
    ----------
    system : quadcosim.orchestrator.System
    title : str, optional
        First line of the title.

    Returns
    -------
    matplotlib.figure.Figure
        One axis, its limits holding every box, arrow and label.
    """
    import matplotlib.pyplot as plt

    order, links, constants = _wiring(system)
    column = {name: i for i, name in enumerate(order)}
    box = _box_height(links, column)
    arrows = _route(order, links, column, box)
    lanes = {side: max([a.lane + 1 for a in arrows if a.side == side], default=0) for side in (1, -1)}
    top = box / 2 + LANE * lanes[1] + (LINE * 1.5 if lanes[1] else 0.2)
    bottom = -(box / 2 + LANE * lanes[-1] + 0.25)
    left, right = -0.3, COLUMN * (len(order) - 1) + WIDTH + 0.3
    fig, ax = plt.subplots(figsize=((right - left) * INCH, (top - bottom) * INCH))
    fig.subplots_adjust(0, 0, 1, 1)
    ax.set_xlim(left, right)
    ax.set_ylim(bottom, top)
    ax.axis("off")
    _draw_blocks(ax, system, order, constants, box)
    for arrow in arrows:
        _draw_arrow(ax, arrow, column)
    links_drawn = sum(1 for dst, src in system.connections.items() if src.split(".", 1)[0] in order)
    heading = f"{blocks_text(system)}, {links_drawn} connections, macro step {system.dt * 1e3:g} ms"
    faults = [f"{f.kind} fault on the input {f.target}, {f.start:g}-{f.stop:g} s" for f in system.faults]
    ax.set_title("\n".join([*([title] if title else []), heading, *faults]), fontsize=9, pad=8)
    return fig


def blocks_text(system) -> str:
    """The system's blocks as counted everywhere (the diagram's heading, a run's status line):
    ``"6 blocks"``, with ``" and 4 constants tying off inputs"`` when it holds such ties (they
    are noted inside the blocks they feed, not drawn)."""
    ties = sum(1 for b in system.blocks.values() if isinstance(b, Constant) and b.ties)
    drawn = len(system.blocks) - ties
    return f"{drawn} block{'s' * (drawn != 1)}" + (f" and {ties} constant{'s' * (ties != 1)} tying off inputs"
                                                    if ties else "")


def _wiring(system):
    """Block names in the order the signals flow; connections grouped by (source, destination)
    block; and the constant ties-off as ``{block: {value: [inputs]}}``."""
    ties = {b.name: b for b in system.blocks.values() if isinstance(b, Constant) and b.ties}
    links: dict[tuple[str, str], list[str]] = defaultdict(list)
    constants: dict[str, dict[float, list[str]]] = defaultdict(lambda: defaultdict(list))
    for dst, src in system.connections.items():
        src_block, src_name = src.split(".", 1)
        dst_block, dst_name = dst.split(".", 1)
        if src_block in ties:
            tie = ties[src_block]
            constants[dst_block][float(tie.values[tie.outputs.index(src_name)])].append(dst_name)
            continue
        if src_block != dst_block:
            links[(src_block, dst_block)].append(src_name if src_name == dst_name else f"{src_name}→{dst_name}")
    names = [n for n in system.blocks if n not in ties]
    return flow_order(names, list(links)), links, constants


def flow_order(names: list[str], edges: list[tuple[str, str]]) -> list[str]:
    """Blocks in the order the signals flow: a depth-first walk from the blocks nothing feeds
    marks the edges that close a loop (feedbacks); the others are sorted topologically, ties
    kept in the order of ``names``.

    Parameters
    ----------
    names : list of str
        Block names, in the order they were added.
    edges : list of (str, str)
        (source, destination) block pairs.

    Returns
    -------
    list of str
        ``names`` reordered.
    """
    after = {n: [d for s, d in edges if s == n] for n in names}
    fed = {d for _, d in edges}
    state, back = {}, set()  # state: 1 on the walk's path, 2 done

    def walk(node):
        state[node] = 1
        for child in after[node]:
            if state.get(child) == 1:
                back.add((node, child))
            elif child not in state:
                walk(child)
        state[node] = 2

    for root in [n for n in names if n not in fed] + names:
        if root not in state:
            walk(root)
    kept = [(s, d) for s, d in edges if (s, d) not in back]
    ordered, placed = [], set()
    while len(ordered) < len(names):
        ready = next(n for n in names if n not in placed and all(s in placed for s, d in kept if d == n))
        ordered.append(ready)
        placed.add(ready)
    return ordered


def _wrapped(label: str) -> str:
    """A label cut into lines that fit the gap between two blocks, at its commas."""
    import textwrap

    return "\n".join(textwrap.wrap(label, int((COLUMN - WIDTH - 0.2) / CHAR), break_long_words=False))


def _box_height(links, column) -> float:
    """Box height (axis units): room for the tallest label of an arrow to the next block."""
    lines = [_wrapped(fold(names)).count("\n") + 1 for (s, d), names in links.items() if column[d] - column[s] == 1]
    return max(1.1, LINE * max(lines, default=1) * 2 + 0.3)


def _route(order, links, column, box) -> list[Arrow]:
    """Arrows with their side, lane and ports: ports on a box side are sorted so that nested
    arrows do not cross; the shortest arrows take the lanes nearest the row."""
    arrows = []
    for (src, dst), names in links.items():
        step = column[dst] - column[src]
        arrows.append(Arrow(src, dst, fold(names), side=0 if step == 1 else (1 if step > 1 else -1), box=box))
    ends: dict[tuple[str, int], list[tuple[Arrow, str]]] = defaultdict(list)
    for arrow in arrows:
        if arrow.side:
            ends[(arrow.source, arrow.side)].append((arrow, "x0"))
            ends[(arrow.destination, arrow.side)].append((arrow, "x1"))
    for (block, _), members in ends.items():
        left = column[block] * COLUMN
        members.sort(key=partial(_port_order, column, column[block]))
        for k, (arrow, end) in enumerate(members):
            setattr(arrow, end, left + WIDTH * (k + 1) / (len(members) + 1))
    for side in (1, -1):
        taken: list[list[tuple[float, float]]] = []
        for arrow in sorted((a for a in arrows if a.side == side), key=lambda a: abs(a.x1 - a.x0)):
            span = _extent(arrow)
            lane = next((k for k, used in enumerate(taken) if all(span[1] < a or span[0] > b for a, b in used)),
                        len(taken))
            if lane == len(taken):
                taken.append([])
            taken[lane].append(span)
            arrow.lane = lane
    for arrow in arrows:
        if arrow.side:
            arrow.label_x = _label_place(arrow, arrows)
    return arrows


def _label_place(arrow: Arrow, arrows: list[Arrow]) -> float:
    """Centre of an arrow's label on its run: the place nearest the middle where no other
    arrow's vertical run crosses the label (the middle if there is none)."""
    low, high = sorted((arrow.x0, arrow.x1))
    half = CHAR * len(arrow.label) / 2 + 0.1
    crossing = [x for a in arrows if a.side == arrow.side and a.lane > arrow.lane for x in (a.x0, a.x1)]
    middle = (low + high) / 2
    if high - low < 2 * half:
        return middle
    candidates = sorted((low + half + k * 0.1 for k in range(int((high - low - 2 * half) / 0.1) + 1)),
                        key=lambda x: abs(x - middle))
    return next((x for x in candidates if all(abs(x - c) > half for c in crossing)), middle)


def _port_order(column, here: int, member) -> tuple[bool, int]:
    """Sort key of the arrow ends on one side of a box: leftward arrows first, the nearest
    leftmost; then rightward ones, the farthest leftmost (so nested arrows do not cross)."""
    arrow, end = member
    far = column[arrow.destination if end == "x0" else arrow.source]
    return far > here, -far


def _extent(arrow: Arrow) -> tuple[float, float]:
    """Horizontal extent of an arrow's run and its label, with a margin (axis units)."""
    low, high = sorted((arrow.x0, arrow.x1))
    middle, half = (low + high) / 2, CHAR * len(arrow.label) / 2
    return min(low, middle - half) - 0.15, max(high, middle + half) + 0.15


def _draw_blocks(ax, system, order, constants, box):
    from matplotlib.patches import FancyBboxPatch

    for k, name in enumerate(order):
        block = system.blocks[name]
        x = k * COLUMN
        shade = "#dbe8f5" if isinstance(block, FMUBlock) else "#f3f3f3"
        ax.add_patch(FancyBboxPatch((x, -box / 2), WIDTH, box, boxstyle="round,pad=0.02",
                                    facecolor=shade, edgecolor="#333333", zorder=2))
        kind = _kind(block)
        rate = f", every {block.period} steps" if block.period > 1 else ""
        ax.text(x + WIDTH / 2, 0.12 * box, name, ha="center", va="center", fontsize=10, weight="bold", zorder=3)
        ax.text(x + WIDTH / 2, -0.12 * box, kind + rate, ha="center", va="center", fontsize=7, zorder=3)
        if constants.get(name):
            note = "; ".join(f"{fold(names)} = {value:g}" for value, names in constants[name].items())
            ax.text(x + WIDTH / 2, -0.34 * box, note, ha="center", va="center", fontsize=6, color="#666666",
                    zorder=3)


def _draw_arrow(ax, arrow: Arrow, column):
    """A straight arrow to the next block, or three runs (out, along its lane, in) with its
    label just above the horizontal run."""
    colour = FEEDBACK if arrow.side < 0 else FORWARD
    style = dict(color=colour, lw=1.1, linestyle="--" if arrow.side < 0 else "-", zorder=1)
    text = dict(fontsize=FONT, color=colour, ha="center", zorder=4)
    if arrow.side == 0:
        x0, x1 = column[arrow.source] * COLUMN + WIDTH, column[arrow.destination] * COLUMN
        ax.annotate("", xy=(x1, 0.0), xytext=(x0, 0.0), arrowprops=dict(arrowstyle="-|>", **style))
        ax.text((x0 + x1) / 2, 0.06, _wrapped(arrow.label), va="bottom", **text)
        return
    edge, level = arrow.side * arrow.box / 2, arrow.level
    ax.plot([arrow.x0, arrow.x0, arrow.x1], [edge, level, level], **style)
    ax.annotate("", xy=(arrow.x1, edge), xytext=(arrow.x1, level), arrowprops=dict(arrowstyle="-|>", **style))
    ax.text(arrow.label_x, level + 0.04, arrow.label, va="bottom",
            bbox=dict(boxstyle="square,pad=0.05", facecolor="white", edgecolor="none"), **text)
