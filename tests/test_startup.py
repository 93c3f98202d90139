"""Start-up: the command line imports heavy packages only where it uses them (not a timed test)."""

import ast
import subprocess
import sys

import pytest
from quadcosim.benchmarks.startup import imported_modules

from quadcosim import scenarios

NOT_FOR_LISTING = ("control", "dask", "distributed", "matplotlib", "pyarrow", "scipy.optimize", "scipy.signal")


@pytest.mark.parametrize("command", [["list"], ["--help"]])
def test_listing_and_help_import_no_heavy_package(command):
    imported = imported_modules(command)
    if command == ["list"]:
        assert "quadcosim.studies.gain_study" in imported  # the hook saw the options of every scenario
    assert [m for m in NOT_FOR_LISTING if m in imported] == []
    if command == ["--help"]:  # the parser names the verbs; their estimators load when one is run
        assert "numba" not in imported and "estimators" not in imported


@pytest.mark.parametrize("given, seen", [(None, "1"), ("3", "3")])
def test_the_command_starts_one_blas_thread_unless_told(given, seen):
    """numpy's and scipy's OpenBLAS spin a thread per core at load: the command asks for one
    before numpy loads; a user's own setting is kept."""
    import os

    environment = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if given:
        environment["OPENBLAS_NUM_THREADS"] = given
    code = ("import os, sys, quadcosim.cli as command; assert 'numpy' not in sys.modules, 'numpy before the setting'; "
            "print(os.environ.get('OPENBLAS_NUM_THREADS', 'unset')); "
            "command.main = lambda *argv: print(os.environ['OPENBLAS_NUM_THREADS'], 'numpy' in sys.modules) or 0; "
            "command.entry()")
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True, env=environment)
    # importing the module changes nothing (a program that imports it keeps its environment); the command sets it
    assert out.stdout.split() == [given or "unset", seen, "False"]


def test_a_scenario_look_up_imports_that_scenario_alone():
    code = ("import sys, quadcosim.scenarios; quadcosim.scenarios.get('open-loop'); "
            "print(sorted(m for m in sys.modules if m.startswith('quadcosim.scenarios.')))")
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout
    imported = ast.literal_eval(out)
    assert "quadcosim.scenarios.open_loop" in imported
    others = [module for name, (module, _) in scenarios.catalogue.registrations().items() if name != "open-loop"]
    assert [m for m in others if m in imported] == []
    assert scenarios.names() == tuple(scenarios.registry())
    with pytest.raises(KeyError, match="Did you mean tp"):
        scenarios.get("tpp")


def test_a_short_tp_run_imports_no_optimiser(tmp_path):
    """The cruise trim and the report's drag findings import scipy.optimize only where used:
    a default ``tp`` run (flight quasi, no wind) imports none of it (start-up)."""
    imported = imported_modules(["run", "tp", "--set", "duration=0.05", "--out", str(tmp_path / "tp")])
    assert "scipy.optimize" not in imported
    assert "matplotlib" in imported  # its report's figures, drawn
