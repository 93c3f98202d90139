"""Signal names: the vectors among them, a matrix's shape, a vector's components, their units.

A recorded signal is ``"Block.signal"``; a vector's components are ``NAME_x``, ``NAME_y``,
``NAME_z`` or ``NAME0``, ``NAME1``, ... (``NAME_1`` too), a rotation matrix's ``NAME_11`` to
``NAME_33``.
"""

from __future__ import annotations

import re

# a component: "acc_x" (axis after an underscore), "q0", "omega_r1", "R_reel_11" (index)
_COMPONENT = re.compile(r"^(?P<base>.+?)(?:_(?P<axis>[xyz])|_?(?P<index>\d+))$")


def vector_groups(names) -> dict[str, list[str]]:
    """The vectors among signal names, each with its components in order.

    Components are ``NAME_x``, ``NAME_y``, ``NAME_z`` or ``NAME0``, ``NAME1``, ... (``NAME_1``
    too) of one block; at least two make a vector. A vector whose name is itself a signal is
    left out.

    Parameters
    ----------
    names : sequence of str
        ``"Block.signal"`` names.

    Returns
    -------
    dict of str to list of str
        ``{"IMU.acc": ["IMU.acc_x", "IMU.acc_y", "IMU.acc_z"], "IMU.R_reel": [...9 names], ...}``
        in the order of first appearance.
    """
    groups: dict[str, list[tuple]] = {}
    for name in names:
        block, dot, signal = name.partition(".")
        match = _COMPONENT.match(signal)
        if dot and match:
            key = "xyz".index(match["axis"]) if match["axis"] else int(match["index"])
            groups.setdefault(f"{block}.{match['base']}", []).append((key, name))
    taken = set(names)
    return {vector: [name for _, name in sorted(members)] for vector, members in groups.items()
            if len(members) > 1 and vector not in taken}


def matrix_shape(components: list[str]) -> tuple[int, ...]:
    """``(3, 3)`` for the nine components ``_11`` to ``_33`` of a rotation matrix, row by row;
    ``(k,)`` for any other vector of ``k`` components."""
    indices = [_COMPONENT.match(c.partition(".")[2])["index"] for c in components]
    if len(components) == 9 and indices == [f"{i}{j}" for i in "123" for j in "123"]:
        return (3, 3)
    return (len(components),)


def signal_units(blocks, names) -> dict[str, str]:
    """The unit of each recorded signal, from its block: an FMU's model description, or the
    ``units`` dictionary a Python block declares (``""`` where none is known).

    Parameters
    ----------
    blocks : dict of str to block
        The system's blocks by name (``System.blocks``).
    names : sequence of str
        Recorded ``"Block.signal"`` names.

    Returns
    -------
    dict of str to str
        Unit of each name, e.g. ``{"IMU.acc_x": "m/s2"}``.
    """
    units = {}
    for name in names:
        block, _, signal = name.partition(".")
        units[name] = str(getattr(blocks.get(block), "units", {}).get(signal, "") or "")
    return units


def signal_dtypes(blocks, names) -> dict[str, str]:
    """The NumPy type of each recorded signal that is not float64, from its block's ``dtypes``
    (an FMU's integer, Boolean and single-precision signals: :func:`quadcosim.orchestrator.fmi_types.dtypes`).

    Parameters
    ----------
    blocks : dict of str to block
        The system's blocks by name.
    names : sequence of str
        Recorded ``"Block.signal"`` names.

    Returns
    -------
    dict of str to str
        ``{"Stair.counter": "int32"}``; a float64 signal is left out.
    """
    found = {}
    for name in names:
        block, _, signal = name.partition(".")
        dtype = getattr(blocks.get(block), "dtypes", {}).get(signal)
        if dtype:
            found[name] = dtype
    return found


def expand(name: str, available) -> list[str]:
    """Names a signal name stands for: itself, or its components.

    ``"IMU.acc"`` stands for ``IMU.acc_x``, ``IMU.acc_y``, ``IMU.acc_z``;
    ``"MotorMagnetics.omega_r"`` for ``omega_r1`` to ``omega_r4``; ``"Quadrotor.q"`` for
    ``q0`` to ``q3``; ``"IMU.R_reel"`` for ``R_reel_11`` to ``R_reel_33``.

    Parameters
    ----------
    name : str
        A signal or vector name.
    available : sequence of str
        The names to choose from.

    Returns
    -------
    list of str
        The matching names, in the order of ``available``; empty if none.
    """
    available = list(available)
    if name in available:
        return [name]
    members = [s for s in available if s.startswith(name) and _is_component(s[len(name):])]
    return members


def _is_component(suffix: str) -> bool:
    if suffix.startswith("_"):
        suffix = suffix[1:]
    return bool(suffix) and (suffix in ("x", "y", "z") or suffix.isdigit())
