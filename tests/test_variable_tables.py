"""Variable tables and the shell: names, not positions; SI base units; a failed step.

The C models address vectors (a quaternion, rotor speeds, field directions) as arrays from
their first member, so the build checks that each vector's rows are consecutive. A table
reordered without splitting a vector builds into an FMU that gives identical results by name;
a table that splits one is refused with a message that names it.
"""

import dataclasses

import numpy as np
import pytest
from fmpy import read_model_description
from quadcosim.fmus import MODELS, fmu_path
from quadcosim.fmus.build import BuildError, build_fmu, table
from quadcosim.fmus.models import sensor, sensors
from quadcosim.fmus.variables import base_unit
from quadcosim.orchestrator.fmu import FMUInstance


def held(model: str) -> tuple[dict, dict]:
    """The inputs held over the check and the parameters of the run: the model's ``HELD_INPUTS``
    and ``HELD_PARAMETERS`` (its folder's ``__init__.py``; for the plant, a rotating, tilted body
    with the motors unequal)."""
    member = sensor(model)
    return member.check("HELD_INPUTS"), member.check("HELD_PARAMETERS")


def _units(tab):
    """The table's rows as units that keep vectors whole: each vector, then each other variable."""
    first, inside = {}, set()
    for members in sorted(tab.vectors().values(), key=len, reverse=True):  # v1..v4 lie inside v
        if members[0].name not in inside:
            first[members[0].name] = members
            inside |= {v.name for v in members}
    units = []
    for v in tab.variables:
        if v.name in first:
            units.append(list(first[v.name]))
        elif v.name not in inside:
            units.append([v])
    return units


def _reordered(tab, units):
    return dataclasses.replace(tab, variables=[v for unit in units for v in unit])


def _run(path, model, steps=300, h=1e-3):
    inputs, parameters = held(model)
    fmu = FMUInstance(str(path), parameters, name=model)
    try:
        names, values = list(inputs), list(inputs.values())
        rows = []
        for k in range(steps):
            fmu.set(names, values)
            rows.append(fmu.get(fmu.outputs))
            fmu.step(k * h, h)
        return {name: column for name, column in zip(fmu.outputs, np.array(rows).T, strict=True)}
    finally:
        fmu.close()


@pytest.mark.parametrize("model", MODELS)
def test_a_table_reordered_without_splitting_a_vector_gives_identical_results(model, tmp_path):
    tab = table(model)
    reordered = _reordered(tab, _units(tab)[::-1])
    assert [tab.vr[v.name] for v in tab.variables] != [reordered.vr[v.name] for v in tab.variables]  # it did move
    expected = _run(fmu_path(model), model)
    got = _run(build_fmu(model, tmp_path, variables=reordered), model)
    assert got.keys() == expected.keys()
    for name in expected:
        assert np.array_equal(got[name], expected[name]), name


@pytest.mark.parametrize(("model", "vector"), [(name, member.check("SPLIT_VECTOR"))
                                               for name, member in sensors().items() if member.check("SPLIT_VECTOR")])
def test_a_table_that_splits_a_vector_is_refused_by_the_build(model, vector, tmp_path):
    """Each model's ``SPLIT_VECTOR`` (a vector of three rows or more), split."""
    tab = table(model)
    units = _units(tab)
    index = next(k for k, unit in enumerate(units) if len(unit) > 1 and unit[0].name.startswith(vector))
    members = units.pop(index)
    units.insert(index, members[:2])
    units.append(members[2:])  # the tail of the vector moves to the end of the table
    with pytest.raises(BuildError, match=rf"vector {vector} .* must be consecutive rows .* Move its rows together"):
        build_fmu(model, tmp_path, variables=_reordered(tab, units))


@pytest.mark.parametrize(("model", "vector"), [(name, member.check("SPLIT_VECTOR"))
                                               for name, member in sensors().items() if member.check("SPLIT_VECTOR")])
def test_a_vector_out_of_component_order_is_refused(model, vector, tmp_path):
    tab = table(model)
    members = [v.name for v in tab.vectors()[vector]]
    variables = list(tab.variables)
    names = [v.name for v in variables]
    i, j = names.index(members[1]), names.index(members[2])
    variables[i], variables[j] = variables[j], variables[i]
    swapped = [members[0], members[2], members[1], *members[3:]]
    with pytest.raises(BuildError, match=f"members of vector {vector} are out of order in the table: "
                                         f"{', '.join(swapped)}"):
        build_fmu(model, tmp_path, variables=dataclasses.replace(tab, variables=variables))


@pytest.mark.parametrize(("unit", "expected"), [
    ("T", {"kg": 1, "s": -2, "A": -1}),
    ("N.m.s2", {"kg": 1, "m": 2}),
    ("V.s/rad", {"kg": 1, "m": 2, "s": -2, "A": -1, "rad": -1}),
    ("m/s2", {"m": 1, "s": -2}),
    ("1", {}),
    ("rad/s/Hz0.5", None),  # s^-1/2: no integer exponents in FMI 2.0
])
def test_si_base_units(unit, expected):
    assert base_unit(unit) == expected


@pytest.mark.parametrize("model", MODELS)
def test_every_unit_definition_declares_its_si_base_unit(model):
    description = read_model_description(str(fmu_path(model)))
    definitions = {u.name: u for u in description.unitDefinitions}
    used = {v.unit for v in table(model).variables if v.unit}
    assert set(definitions) == used
    for name, definition in definitions.items():
        if "Hz0.5" in name:
            assert definition.baseUnit is None
            continue
        base = definition.baseUnit
        declared = {k: getattr(base, k) for k in ("kg", "m", "s", "A", "K", "mol", "cd", "rad") if getattr(base, k)}
        assert declared == base_unit(name), name
        assert base.factor == 1.0 and base.offset == 0.0
