"""The scenarios by name: one line each, the name and the module declaring its ``SCENARIO``.

A look-up imports the named module alone (:func:`get`), so that listing one scenario's options
does not load every scenario. The scenarios of this package are listed in :data:`MODULES`; a
package above (the studies) registers its own with :func:`register` when it is imported, so
that this package never names a module of a floor above it. The command line imports those
packages before it reads the catalogue.
"""

from __future__ import annotations

import importlib

#: Scenario name -> the module of this package declaring it (its ``SCENARIO``).
MODULES = {
    "open-loop": "scenarios.open_loop",
    "rig": "scenarios.rig",
    "tp": "scenarios.tp",
    "static-cal": "scenarios.static_cal",
    "metge": "scenarios.metge",
    "ir-calibration": "scenarios.ir_calibration",
}
# scenario name -> (module, the package that registered it), in the order of listing
_REGISTERED: dict[str, tuple[str, str]] = {name: (module, __name__) for name, module in MODULES.items()}


def register(name: str, module: str, registrant: str) -> None:
    """Add a scenario declared by a package above this one (its ``__init__`` calls this).

    Parameters
    ----------
    name : str
        The scenario's name, as ``quadcosim run NAME`` takes it.
    module : str
        The module declaring its ``SCENARIO``, imported when the scenario is asked for.
    registrant : str
        The registering module (its ``__name__``): the architecture test checks that it may
        import ``module``.

    Raises
    ------
    ValueError
        ``name`` is registered already, to another module.
    """
    known = _REGISTERED.get(name)
    if known is not None and known[0] != module:
        raise ValueError(f"scenario {name!r} is registered already, by {known[1]} ({known[0]})")
    _REGISTERED[name] = (module, registrant)


def unregister(name: str) -> None:
    """Remove a registered scenario (a test's dummy); the package's own stay.

    Parameters
    ----------
    name : str
        The registered scenario's name.
    """
    if name in MODULES:
        raise ValueError(f"scenario {name!r} is one of this package's own")
    _REGISTERED.pop(name, None)


def registrations() -> dict[str, tuple[str, str]]:
    """Every scenario's ``(module, registering module)``, by name."""
    return dict(_REGISTERED)


def names() -> tuple[str, ...]:
    """The scenarios' names, without importing any scenario module."""
    return tuple(_REGISTERED)


def get(name: str):
    """The scenario called ``name`` (a :class:`scenarios.Scenario`), importing its module only.

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
    if name not in _REGISTERED:
        from orchestrator.fmu import nearest

        raise KeyError(f"unknown scenario {name!r}.{nearest(name, _REGISTERED)} Scenarios: {', '.join(_REGISTERED)}.")
    module = _REGISTERED[name][0]
    scenario = importlib.import_module(module).SCENARIO
    if scenario.name != name:
        raise RuntimeError(f"{module} declares {scenario.name!r}, registered as {name!r}")
    return scenario


def registry() -> dict:
    """Every scenario, by name (imports every scenario module; :func:`get` imports one)."""
    return {name: get(name) for name in _REGISTERED}
