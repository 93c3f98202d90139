"""Block parameters set by name, checked against the FMU's variable table.

``"IMU.gyro_noise_density"`` names one FMU parameter; ``"IMU.b_g"`` a parameter vector
(``b_g_x, b_g_y, b_g_z``), given as three numbers (``"0.01,0,0"`` or a sequence). A model's
variable module may declare ``ALIASES`` (another name for a parameter vector, such as
``gyro_bias`` for ``b_g``) and ``SWITCHED`` (a Boolean parameter and the parameters that act only
while it is true: setting a noise density while the noise is off is refused rather than ignored).

A value given as text may carry the variable's unit after it (``"0.002 rad/s/Hz0.5"``); another
unit is refused with the expected one named. A Python block's parameters reach it through the
block contract (:meth:`quadcosim.orchestrator.Block.parameter_values` and
:meth:`~quadcosim.orchestrator.Block.set_parameter`): the ones its class declares
(:attr:`~quadcosim.orchestrator.Block.parameter_units`, such as the controller's gains,
``Controller.kp_yaw``), else its public numeric attributes (``Quaternion_estim.beta``).

:func:`check_declared` checks settings before any block is built, against what a system will hold
(block name to an FMU model or a block class); :func:`resolve_all` and :func:`set_all` then set
them on the built system.
"""

from __future__ import annotations

import math
import numbers
import re

from quadcosim.orchestrator.blocks import Block, FMUBlock
from quadcosim.orchestrator.fmi_types import INTEGER_TYPES, is_parameter
from quadcosim.orchestrator.fmu import nearest
from quadcosim.orchestrator.signals import expand

_NUMBER = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?inf|nan)\s*(.*)", re.IGNORECASE)


def fmu_parameters(model: str) -> dict:
    """The parameters of a built FMU, by name.

    Parameters
    ----------
    model : str
        FMU model name (``"IMU"``).

    Returns
    -------
    dict
        Name to fmpy's variable (``type``, ``start``, ``unit``, ``description``).
    """
    from quadcosim.orchestrator.fmu import fmu_file, model_description

    description = model_description(fmu_file(model))
    return {v.name: v for v in description.modelVariables if is_parameter(v)}


def model_notes(model: str) -> tuple[dict, dict]:
    """``ALIASES`` and ``SWITCHED`` of ``fmus/<model>/variables.py`` (empty if none, as for an
    FMU file of the user's)."""
    from quadcosim.fmus import MODELS, model_variables

    if model not in MODELS:
        return {}, {}
    module = model_variables(model)
    return dict(getattr(module, "ALIASES", {})), dict(getattr(module, "SWITCHED", {}))


def resolve(system, target: str, value) -> dict:
    """Parameter values that ``target = value`` stands for, checked.

    Parameters
    ----------
    system : quadcosim.orchestrator.System
        The system holding the block.
    target : str
        ``"Block.parameter"``: an FMU parameter or parameter vector (or an alias of one), or a
        numeric attribute of a Python block.
    value : str, number, bool or sequence
        Text (``"0.01"``, ``"true"``, ``"0.01,0,0"``, optionally followed by the unit) or values.

    Returns
    -------
    dict
        Parameter name (within the block) to its value, one entry per component.

    Raises
    ------
    KeyError
        Unknown block or parameter; the message names the nearest names.
    ValueError
        A value of the wrong type, count or unit.
    """
    block_name, dot, name = target.partition(".")
    if not dot or not name:
        raise ValueError(f"{target!r}: write Block.parameter=value, e.g. IMU.gyro_noise_density=0.001")
    block = system.blocks.get(block_name)
    if block is None:
        raise KeyError(f"unknown block {block_name!r} in {target!r}.{nearest(block_name, system.blocks)} "
                       f"Blocks: {', '.join(system.blocks)}.")
    if not isinstance(block, FMUBlock):
        return {name: _python_value(block, name, value)}
    variables = fmu_parameters(block.model)
    aliases, _ = model_notes(block.model)
    members = expand(aliases.get(name, name), variables)
    if not members:
        listed = list(variables) + list(aliases)
        raise KeyError(f"{block_name} has no parameter {name!r}.{nearest(name, listed)} Its parameters are listed, "
                       f"with their units, by `quadcosim list --parameters {block.model}`.")
    texts = _components(target, value, len(members))
    return {m: _parse(f"{block_name}.{m}", variables[m], t) for m, t in zip(members, texts, strict=True)}


def apply(system, settings: dict, options: dict | None = None) -> dict:
    """Set block parameters on ``system`` before its run: :func:`resolve_all`, then :func:`set_all`.

    Parameters
    ----------
    system : quadcosim.orchestrator.System
    settings : dict
        ``{"Block.parameter": value}``, each as :func:`resolve` takes it.
    options : dict, optional
        ``{"Block.parameter": "option"}``: the scenario option that sets a parameter, named in
        messages (``IMU.noise_enabled`` is set by ``tp``'s option ``noise``).

    Returns
    -------
    dict
        The values set, as they will be used: a number, or a list for a vector.

    Raises
    ------
    KeyError, ValueError
        As :func:`resolve`; or a parameter set while the switch it needs is off.
    """
    return set_all(system, resolve_all(system, settings), options)


def resolve_all(system, settings: dict) -> dict[str, dict]:
    """Every setting resolved (:func:`resolve`), once: ``{"Block.parameter": {name: value}}``.

    Parameters
    ----------
    system : quadcosim.orchestrator.System
    settings : dict
        ``{"Block.parameter": value}``.

    Returns
    -------
    dict
        Each target to its parameter values within the block, one entry per component.
    """
    return {target: resolve(system, target, value) for target, value in settings.items()}


def set_all(system, resolved: dict[str, dict], options: dict | None = None) -> dict:
    """Set resolved parameter values (:func:`resolve_all`) on ``system``'s blocks.

    Parameters
    ----------
    system : quadcosim.orchestrator.System
    resolved : dict
        ``{"Block.parameter": {name: value}}``.
    options : dict, optional
        ``{"Block.parameter": "option"}``, named in messages (see :func:`apply`).

    Returns
    -------
    dict
        The values set, as they will be used: a number, or a list for a vector.

    Raises
    ------
    ValueError
        A parameter set while the switch it needs is off.
    """
    used = {}
    for target, values in resolved.items():
        block = system.blocks[target.partition(".")[0]]
        if isinstance(block, FMUBlock):
            block.parameters.update(values)
        else:
            for name, v in values.items():
                block.set_parameter(name, v)
        used[target] = list(values.values()) if len(values) > 1 else next(iter(values.values()))
    for target in resolved:
        _check_switch(system, target, options or {})
    return used


def _check_switch(system, target: str, options: dict):
    block_name, _, name = target.partition(".")
    block = system.blocks[block_name]
    if not isinstance(block, FMUBlock):
        return
    aliases, switched = model_notes(block.model)
    name = aliases.get(name, name)
    variables = None
    for switch, governed in switched.items():
        if any(expand(g, [name]) for g in governed):
            variables = variables or fmu_parameters(block.model)
            on = block.parameters.get(switch, variables[switch].start)
            if str(on).lower() not in ("true", "1"):
                option = options.get(f"{block_name}.{switch}")
                fix = f"--set {option}=true" if option else f"--set {block_name}.{switch}=true"
                raise ValueError(f"{target} has no effect while {block_name}.{switch} is false: turn it on ({fix})")


def _components(target: str, value, count: int) -> list:
    if isinstance(value, str):
        parts = [p.strip() for p in value.strip().strip("()[]").split(",")]
    elif isinstance(value, (list, tuple)) or hasattr(value, "__array__"):
        parts = list(value)
    else:
        parts = [value]
    if len(parts) != count:
        raise ValueError(f"{target} has {count} component{'s' * (count > 1)}: give {count} value"
                         f"{'s' * (count > 1)}{', comma-separated' if count > 1 else ''}, not {len(parts)}")
    return parts


def _parse(label: str, variable, value):
    """The value of one FMU parameter from text or a number, checked against its type and unit."""
    kind = variable.type
    if kind in ("String", "Binary"):  # text as given (a Binary as hexadecimal text or bytes)
        return value if isinstance(value, bytes | bytearray) else str(value)
    if kind == "Boolean":
        text = str(value).strip().lower()
        if text in ("1", "true", "on", "yes"):
            return True
        if text in ("0", "false", "off", "no"):
            return False
        raise ValueError(f"{label} = {value!r}: give true or false")
    if isinstance(value, str):
        match = _NUMBER.fullmatch(value)
        if not match:
            raise ValueError(f"{label} = {value!r} is not a number{_unit_hint(variable)}")
        number, unit = match.group(1), match.group(2).strip()
        expected = variable.unit or ""
        if unit and unit != expected:
            raise ValueError(f"{label} = {value!r}: the unit is {expected or 'none (a pure number)'}, not {unit!r}; "
                             f"give the value in {expected or 'no unit'}")
        value = number
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{label} = {value!r} is not a number{_unit_hint(variable)}") from None
    if not math.isfinite(number):
        raise ValueError(f"{label} = {value!r} must be a finite number{_unit_hint(variable)}")
    if kind in INTEGER_TYPES:
        if number != int(number):
            raise ValueError(f"{label} = {value!r} must be an integer")
        return int(number)
    return number


def _unit_hint(variable) -> str:
    return f" (in {variable.unit})" if variable.unit else ""


def python_parameters(block) -> dict:
    """A Python block's settable parameters and their present values.

    Parameters
    ----------
    block : quadcosim.orchestrator.Block
        A Python block.

    Returns
    -------
    dict
        Name to value, sorted by name (:meth:`quadcosim.orchestrator.Block.parameter_values`).
    """
    return dict(sorted(block.parameter_values().items()))


def _python_value(block, name: str, value):
    values = python_parameters(block)
    if name not in values:
        raise KeyError(f"{block.name} has no parameter {name!r}.{nearest(name, values)} "
                       f"{'Its parameters: ' + ', '.join(values) if values else 'It has no numeric parameter'}"
                       " (a Python block's parameters are the ones its class declares, else its public numeric "
                       "attributes).")
    present = values[name]
    label = f"{block.name}.{name}"
    if isinstance(present, bool):
        text = str(value).strip().lower()
        if text not in ("1", "true", "on", "yes", "0", "false", "off", "no"):
            raise ValueError(f"{label} = {value!r}: give true or false")
        return text in ("1", "true", "on", "yes")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{label} = {value!r} is not a number") from None
    if not math.isfinite(number):
        raise ValueError(f"{label} = {value!r} must be a finite number")
    if isinstance(present, numbers.Integral):
        if number != int(number):
            raise ValueError(f"{label} = {value!r} must be an integer")
        return int(number)
    return number


def check_declared(blocks: dict, settings: dict) -> tuple[dict[str, dict], list[str]]:
    """Settings checked before any block is built, against the blocks a system will hold.

    Parameters
    ----------
    blocks : dict
        Block name to what the block will be: an FMU model's name or an FMU file's path (its
        variable table is read), or a :class:`quadcosim.orchestrator.Block` class (its declared
        :attr:`~quadcosim.orchestrator.Block.parameter_units`).
    settings : dict
        ``{"Block.parameter": value}``, each as :func:`resolve` takes it.

    Returns
    -------
    resolved : dict
        ``{"Block.parameter": {name: value}}`` for each setting checked (as :func:`resolve_all`).
    deferred : list of str
        The settings of blocks whose class declares no parameters (its public numeric
        attributes are known once it is built): checked by :func:`resolve` on the built system.

    Raises
    ------
    KeyError
        An unknown block or parameter; the message names the nearest names and where the
        parameters are listed.
    ValueError
        A value of the wrong type, count or unit.
    """
    resolved, deferred = {}, []
    for target, value in settings.items():
        block_name, dot, name = target.partition(".")
        if not dot or not name:
            raise ValueError(f"{target!r}: write Block.parameter=value, e.g. IMU.gyro_noise_density=0.001")
        if block_name not in blocks:
            raise KeyError(f"unknown block {block_name!r} in {target!r}.{nearest(block_name, blocks)} "
                           f"Blocks: {', '.join(blocks)}.")
        model = blocks[block_name]
        if isinstance(model, type) and issubclass(model, Block):
            if not model.parameter_units:
                deferred.append(target)
                continue
            resolved[target] = {name: _declared_value(block_name, model, name, value)}
            continue
        variables = fmu_parameters(str(model))
        aliases, _ = model_notes(str(model))
        members = expand(aliases.get(name, name), variables)
        if not members:
            raise KeyError(f"{block_name} has no parameter {name!r}.{nearest(name, list(variables) + list(aliases))} "
                           "Its parameters are listed, with their units, by `quadcosim list --parameters "
                           f"{model}`.")
        texts = _components(target, value, len(members))
        resolved[target] = {m: _parse(f"{block_name}.{m}", variables[m], t)
                            for m, t in zip(members, texts, strict=True)}
    return resolved, deferred


class _Declared:
    """A declared parameter of a Python block, read as :func:`_parse` reads an FMU variable."""

    type = "Real"

    def __init__(self, unit: str):
        self.unit = "" if unit == "1" else unit


def _declared_value(block_name: str, cls: type, name: str, value) -> float:
    """The value of a parameter ``cls`` declares, a finite number in its declared unit."""
    units = cls.parameter_units
    if name not in units:
        raise KeyError(f"{block_name} has no parameter {name!r}.{nearest(name, units)} Its parameters: "
                       f"{', '.join(units)} (`quadcosim list --parameters {block_name}` gives their units).")
    return cls.check_parameter(name, _parse(f"{block_name}.{name}", _Declared(units[name]), value))
