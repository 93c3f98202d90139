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

from orchestrator.blocks import FMUBlock


def fold(names: list[str]) -> str:
    """Fold vector components: ``[omega_r1, omega_r2, omega_r3, omega_r4]`` -> ``omega_r[1-4]``."""
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
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import FancyBboxPatch

    order = [b for b in system.order() if not b.name.startswith("Const_")]
    position = {b.name: i for i, b in enumerate(order)}
    links: dict[tuple[str, str], list[str]] = defaultdict(list)
    constants: dict[str, list[str]] = defaultdict(list)
    for dst, src in system.connections.items():
        src_block, src_name = src.split(".", 1)
        dst_block, dst_name = dst.split(".", 1)
        if src_block.startswith("Const_"):
            constants[dst_block].append(dst_name)
            continue
        links[(src_block, dst_block)].append(src_name if src_name == dst_name else f"{src_name}→{dst_name}")

    width, height = 2.2, 1.0
    fig, ax = plt.subplots(figsize=(max(8, 3.4 * len(order)), 4.5))
    centres = {}
    for block in order:
        x = position[block.name] * 3.8
        centres[block.name] = (x + width / 2, 0.0)
        shade = "#dbe8f5" if isinstance(block, FMUBlock) else "#f3f3f3"
        ax.add_patch(FancyBboxPatch((x, -height / 2), width, height, boxstyle="round,pad=0.05",
                                    facecolor=shade, edgecolor="#333333"))
        kind = f"FMU {block.model}" if isinstance(block, FMUBlock) else type(block).__name__
        rate = f", every {block.period} steps" if block.period > 1 else ""
        ax.text(x + width / 2, 0.12, block.name, ha="center", va="center", fontsize=10, weight="bold")
        ax.text(x + width / 2, -0.2, kind + rate, ha="center", va="center", fontsize=7)
        if constants.get(block.name):
            ax.text(x + width / 2, height / 2 + 0.15, "0 → " + fold(constants[block.name]), ha="center",
                    fontsize=6, color="#777777")
    for k, ((src, dst), names) in enumerate(sorted(links.items(), key=lambda item: position[item[0][0]])):
        (x0, _), (x1, _) = centres[src], centres[dst]
        forward = position[dst] > position[src]
        skip = position[dst] - position[src] > 1
        if forward and not skip:
            start, end, rad, label_y = (x0 + width / 2, 0.0), (x1 - width / 2, 0.0), 0.0, 0.08
        elif forward:  # over the blocks in between
            start, end, rad = (x0 + 0.3, height / 2), (x1 - 0.3, height / 2), -0.3
            label_y = height / 2 + 0.1 + 0.12 * (position[dst] - position[src])
        else:  # feedback, under the blocks
            start, end, rad = (x0, -height / 2), (x1, -height / 2), -0.35
            label_y = -height / 2 - 0.6 - 0.25 * (k % 3)
        ax.annotate("", xy=end, xytext=start, arrowprops=dict(
            arrowstyle="-|>", color="#1f4e79" if forward else "#a33", lw=1.2,
            linestyle="-" if forward else "--", connectionstyle=f"arc3,rad={rad}"))
        ax.text((start[0] + end[0]) / 2, label_y, fold(names).replace(", ", "\n"), ha="center", va="bottom",
                fontsize=6, color="#1f4e79" if forward else "#a33")
    ax.set_xlim(-0.6, 3.8 * len(order))
    ax.set_ylim(-2.2, 1.3)
    ax.axis("off")
    ax.set_title(f"{len(order)} blocks, {len(system.connections)} connections, macro step {system.dt * 1e3:g} ms")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with matplotlib.rc_context({"svg.fonttype": "none"}):  # SVG text stays text
        fig.savefig(path, dpi=130, bbox_inches="tight")
    plt.close(fig)
    return path
