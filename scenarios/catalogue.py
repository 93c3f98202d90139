"""The scenarios by name: the entry-point group ``quadcosim.scenarios``, one line each, the name
and the module declaring its ``SCENARIO`` (:mod:`quadcosim.infra.members`).

A look-up imports the named module alone (:func:`get`), so that listing one scenario's options
does not load every scenario. This package's scenarios, the studies' (``gain-study``) and a third
party's are registered alike, in their package's ``pyproject.toml``; none registers itself by
being imported.
"""

from __future__ import annotations

from quadcosim.infra import members

#: The entry-point group of the scenarios.
GROUP = members.GROUPS["scenarios"]


def registrations() -> dict[str, tuple[str, str]]:
    """Every scenario's ``(module, registering distribution)``, by name."""
    return dict(members.registered(GROUP))


def names() -> tuple[str, ...]:
    """The scenarios' names, without importing any scenario module."""
    return tuple(members.registered(GROUP))


def get(name: str):
    """The scenario called ``name`` (a :class:`quadcosim.scenarios.Scenario`), importing its module only.

    Parameters
    ----------
    name : str
        Scenario name, e.g. ``"tp"`` (see :func:`names`).

    Raises
    ------
    KeyError
        Unknown name; the message names the nearest. A listed module that is missing, or
        that declares another name, is an error, not a gap.
    """
    known = members.registered(GROUP)
    if name not in known:
        from quadcosim.orchestrator.fmu import nearest

        raise KeyError(f"unknown scenario {name!r}.{nearest(name, known)} Scenarios: {', '.join(known)}.")
    module = known[name][0]
    scenario = members.load(module).SCENARIO
    if scenario.name != name:
        raise RuntimeError(f"{module} declares {scenario.name!r}, registered as {name!r}")
    return scenario


def registry() -> dict:
    """Every scenario, by name (imports every scenario module; :func:`get` imports one)."""
    return {name: get(name) for name in members.registered(GROUP)}
