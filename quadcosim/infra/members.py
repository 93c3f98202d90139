"""The members of the package's closed sets, registered by entry points.

Each closed set (the scenarios, the estimators, the sensor FMUs, the autopilots, the interference
models) is an entry-point group, :data:`GROUPS`. A member is registered by one line in the
``pyproject.toml`` of the package that holds it, this one or a third party's::

    [project.entry-points."quadcosim.scenarios"]
    tp = "quadcosim.scenarios.tp"

The value names the module that holds the member (and, after a colon, the object in it). The
registry reads the names without importing a member; a member's module is imported when that
member is asked for. Nothing registers itself by being imported.
"""

from __future__ import annotations

import functools
import importlib

from quadcosim.infra.errors import UsageError

#: The entry-point group of each closed set.
GROUPS = {
    "scenarios": "quadcosim.scenarios",
    "estimators": "quadcosim.estimators",
    "sensors": "quadcosim.sensors",
    "autopilots": "quadcosim.autopilots",
    "interference": "quadcosim.interference",
}


class MemberConflict(UsageError, ValueError):
    """Two installed packages register one name in one set."""


@functools.cache
def registered(group: str) -> dict[str, tuple[str, str]]:
    """The members of ``group``: name -> (value, the distribution registering it).

    Parameters
    ----------
    group : str
        An entry-point group, one of :data:`GROUPS`' values.

    Returns
    -------
    dict
        In the order the distributions list them, this package's first.

    Raises
    ------
    MemberConflict
        Two distributions register one name with different values.
    """
    from importlib.metadata import distributions

    found: dict[str, tuple[str, str]] = {}
    ours, theirs = [], []
    seen = set()
    for dist in distributions():
        name = dist.metadata["Name"] or "?"
        if name in seen:  # one distribution found twice on the path (an editable install and a checkout)
            continue
        seen.add(name)
        points = [point for point in dist.entry_points if point.group == group]
        (ours if name == "quadcosim" else theirs).append((name, points))
    for owner, points in ours + sorted(theirs, key=lambda pair: pair[0]):
        for point in points:
            known = found.get(point.name)
            if known is not None and known[0] != point.value:
                raise MemberConflict(f"{point.name!r} is registered twice in {group}: {known[0]} by {known[1]} and "
                                     f"{point.value} by {owner}; uninstall one of them")
            found[point.name] = (point.value, owner)
    return found


def load(value: str):
    """The object an entry point's value names: ``module`` or ``module:attribute``.

    Parameters
    ----------
    value : str
        The entry point's value.

    Returns
    -------
    object
        The module, or the attribute of it.
    """
    module, _, attribute = value.partition(":")
    loaded = importlib.import_module(module)
    for part in filter(None, attribute.split(".")):
        loaded = getattr(loaded, part)
    return loaded


class RegistrationRefused(UsageError, TypeError):
    """A registry line that names no member of its set, or a member of another name."""


def loaded(group: str, kind: type, error: type = RegistrationRefused) -> dict:
    """Every member of ``group``, imported and checked: name -> the object its line names.

    Parameters
    ----------
    group : str
        An entry-point group, one of :data:`GROUPS`' values.
    kind : type
        The class every member of the set is an instance of (it has a ``name``).
    error : type
        The exception raised for a line that names no ``kind`` of its own name, or that cannot be
        imported (default :class:`RegistrationRefused`).

    Returns
    -------
    dict
        In the order of :func:`registered`.

    Raises
    ------
    RegistrationRefused
        (or ``error``) A line's module cannot be imported, or names no ``kind`` called as the line.
    """
    found = {}
    for name, (value, owner) in registered(group).items():
        try:
            member = load(value)
        except (ImportError, AttributeError) as failure:
            raise error(f"{group} {name} = {value!r} (registered by {owner}) cannot be loaded: {failure}") \
                from failure
        if not isinstance(member, kind) or getattr(member, "name", None) != name:
            raise error(f"{group} {name} = {value!r} (registered by {owner}) names {member!r}, not a "
                        f"{kind.__module__}.{kind.__qualname__} named {name!r}: fix the line or the member")
        found[name] = member
    return found


def forget() -> None:
    """Read the installed members afresh on the next look-up (after installing a package)."""
    registered.cache_clear()
