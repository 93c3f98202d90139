"""One error root: every exception class the package defines derives from UsageError (exit 2) or
RunError (exit 1) and keeps its built-in base; the command line maps the exit codes in one place."""

import ast
import importlib
import signal
from pathlib import Path

import pytest
from quadcosim.orchestrator.errors import RunInterrupted, SimulationError
from quadcosim.orchestrator.fmu_errors import FMUError, ParameterRefused

from quadcosim.infra.errors import QuadcosimError, RunError, UsageError, exit_code_of

ROOT = Path(__file__).resolve().parent.parent
FOLDERS = ("fmus", "orchestrator", "flightlogs", "estimators", "calibration", "flight", "scenarios", "studies",
           "benchmarks", "quadcosim")

#: Exception classes that are not errors a user meets, and why.
NOT_ERRORS = {
    "quadcosim.orchestrator.plan._Failure": "carries a failure out of the loop, raised again as SimulationError",
    "quadcosim.studies.tune._BudgetSpent": "ends the optimiser's search when its budget is spent",
    "quadcosim.infra.interrupts.Terminated": "SIGTERM as a KeyboardInterrupt: an interrupt, not an error",
    "quadcosim.estimators.checks.NoMagnetometerWarning": "a warning",
}

#: Classes that were a bare Exception: no built-in base to keep.
BARE = {"quadcosim.calibration.flight.models.NotIdentifiable"}


def _module(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    parts = parts[:-1] if parts[-1] == "__init__" else parts
    return ".".join(parts if parts[0] == "quadcosim" else ("quadcosim", *parts))


def _exception_classes():
    """Every class of the package that derives from an exception: a base named ``...Error``,
    ``...Exception``, ``...Interrupt`` or ``...Warning``, or one of these classes."""
    classes = []
    for folder in FOLDERS:
        for path in sorted((ROOT / folder).rglob("*.py")):
            classes += [(f"{_module(path)}.{node.name}", node.name,
                         {base.id for base in node.bases if isinstance(base, ast.Name)})
                        for node in ast.walk(ast.parse(path.read_text())) if isinstance(node, ast.ClassDef)]
    found = {name for name, _, bases in classes if any(b.endswith(("Error", "Exception", "Interrupt", "Warning"))
                                                       for b in bases)}
    while True:  # and what derives from them
        short = {name.rpartition(".")[2] for name in found}
        more = {name for name, _, bases in classes if bases & short} - found
        if not more:
            return sorted(name for name in found if not name.startswith("quadcosim.infra.errors."))  # the roots
        found |= more


CLASSES = _exception_classes()


def test_the_search_finds_the_known_classes():
    assert len(CLASSES) >= 25 and "quadcosim.flightlogs.model.LogError" in CLASSES, CLASSES


@pytest.mark.parametrize("name", CLASSES)
def test_every_exception_class_has_the_root(name):
    module, _, attribute = name.rpartition(".")
    cls = getattr(importlib.import_module(module), attribute)
    assert issubclass(cls, BaseException), name
    if name in NOT_ERRORS:
        assert not issubclass(cls, QuadcosimError), f"{name} is declared not an error: {NOT_ERRORS[name]}"
        return
    assert issubclass(cls, (UsageError, RunError)), f"{name} derives from neither UsageError nor RunError"
    specific = [base for base in cls.__mro__ if base.__module__ == "builtins"
                and base not in (Exception, BaseException, object)]
    assert specific or name in BARE, f"{name} lost its built-in base (ValueError, RuntimeError, OSError...)"


def test_one_name_each():
    """Two unrelated classes of one name would be told apart only by their module."""
    names = [name.rpartition(".")[2] for name in CLASSES]
    assert sorted({n for n in names if names.count(n) > 1}) == []


def test_exit_codes():
    assert exit_code_of(UsageError("x")) == 2 and exit_code_of(RunError("x")) == 1
    assert exit_code_of(ValueError("x")) is None  # a fault: its traceback is shown
    assert exit_code_of(SimulationError("failed")) == 1
    assert exit_code_of(RunInterrupted("stopped", None, signal.SIGTERM)) == 143
    refused = ParameterRefused.__new__(ParameterRefused)  # an FMU's refusal of its parameters: usage, not a run
    assert isinstance(refused, FMUError) and isinstance(refused, ValueError) and exit_code_of(refused) == 2


def test_the_command_line_maps_a_refusal_and_a_failure(capsys):
    from quadcosim.cli import main

    assert main(["run", "no-such-scenario"]) == 2
    assert "quadcosim run no-such-scenario: unknown scenario 'no-such-scenario'" in capsys.readouterr().err
    assert main(["study", "no-such-study"]) == 2
    assert "quadcosim study no-such-study: 'no-such-study': not a study; choose one of" in capsys.readouterr().err
