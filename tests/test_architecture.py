"""Dependencies point one way, floor by floor: each package imports only from the floors below
it (:data:`FLOORS`), and the lower packages only the modules their rule names (:data:`ALLOWED`).

Every import in every module of the package is read from its syntax tree (imports inside
functions included), so a late import cannot hide a dependency.
"""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: The floors, from the ground up: the plant, the master, reading flight logs, estimation and
#: calibration, flight control, the scenarios, the studies over many runs, the benchmarks, the
#: command line, and the maintainer's findings (not shipped).
FLOORS = ("fmus", "orchestrator", "flightlogs", "estimators", "calibration", "flight", "scenarios", "studies",
          "benchmarks", "quadcosim", "findings")
PACKAGES = FLOORS


def _below(package: str) -> tuple[str, ...]:
    """Every package on a floor below ``package``'s, as whole-package rules."""
    return tuple(f"{p}." for p in FLOORS[:FLOORS.index(package)])


# What each package may import from the project, besides itself. A name ending in "." allows
# the whole package; a bare module name allows that module and nothing below it. No package is
# allowed a floor above its own, with one declared exception: `quadcosim findings` hands its
# arguments to the maintainer's tool, which is there only in a source checkout.
ALLOWED = {
    "fmus": (),
    # to find built FMUs only: the package's locating functions, not its build or its models
    "orchestrator": ("fmus",),
    # the one writer of every file, and Ctrl-C surfaced while a reader holds the process
    "flightlogs": ("orchestrator.files", "orchestrator.interrupts"),
    # the block contract, the plant's constants, the flight-log reading layer and the one writer
    "estimators": ("orchestrator.blocks", "flightlogs.", "orchestrator.files", "fmus."),
    "calibration": ("orchestrator.blocks", "flightlogs.", "orchestrator.files", "fmus."),
    # the controller: the block contract, the plant, the estimators' quaternion arithmetic
    "flight": ("fmus.", "orchestrator.", "estimators."),
    "scenarios": _below("scenarios"),
    "studies": _below("studies"),
    "benchmarks": _below("benchmarks"),
    "quadcosim": _below("quadcosim") + ("findings.__main__",),
    "findings": _below("findings"),
}


def _imports(path: Path) -> list[tuple[int, str]]:
    """(line, absolute module name) of every import of a project package in ``path``."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                raise AssertionError(f"{path.relative_to(ROOT)}:{node.lineno}: relative import; write it absolute")
            if node.module in PACKAGES:  # `from fmus import vehicle` imports fmus.vehicle
                found += [(node.lineno, f"{node.module}.{alias.name}") for alias in node.names]
            else:
                found.append((node.lineno, node.module))
    return [(line, name) for line, name in found if name.split(".")[0] in PACKAGES]


def _allowed(layer: str, module: str, package_names: set[str]) -> bool:
    if module.split(".")[0] == layer:
        return True
    for rule in ALLOWED[layer]:
        if rule.endswith(".") and (module + ".").startswith(rule):
            return True
        # `from fmus import fmu_path` names an attribute of the package, not a module
        if module == rule or (module.rsplit(".", 1)[0] == rule and module not in package_names):
            return True
    return False


def _modules() -> set[str]:
    names = set()
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*.py"):
            parts = path.relative_to(ROOT).with_suffix("").parts
            names.add(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return names


def _violations() -> list[str]:
    modules = _modules()
    bad = []
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            for line, module in _imports(path):
                if not _allowed(package, module, modules):
                    bad.append(f"{path.relative_to(ROOT)}:{line} imports {module}")
    return bad


def test_every_import_points_down_the_layers():
    bad = _violations()
    assert not bad, f"imports against the floors {' <- '.join(FLOORS)}:\n" + "\n".join(bad)


def test_the_command_line_and_the_benchmarks_live_in_the_top_layer():
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert project["project"]["scripts"]["quadcosim"] == "quadcosim.main:entry"
    assert "benchmarks*" in project["tool"]["setuptools"]["packages"]["find"]["include"]
    assert not (ROOT / "orchestrator" / "cli.py").exists()
    assert not list((ROOT / "orchestrator").glob("bench*.py"))
    assert not list((ROOT / "estimators").glob("bench*.py"))


@pytest.mark.parametrize(("layer", "module", "expected"), [
    ("orchestrator", "fmus", True),
    ("orchestrator", "fmus.fmu_path", True),
    ("orchestrator", "fmus.build", False),
    ("orchestrator", "scenarios", False),
    ("fmus", "orchestrator.fmu", False),
    ("estimators", "orchestrator.blocks", True),
    ("estimators", "orchestrator.system", False),
    ("calibration", "flightlogs.model", True),
    ("calibration", "orchestrator.fmu", False),
    ("estimators", "scenarios.plant", False),
    ("scenarios", "benchmarks.master", False),
    ("benchmarks", "scenarios.tp", True),
    ("scenarios", "studies.sweep", False),
    ("flightlogs", "orchestrator.files", True),
    ("flightlogs", "calibration.static", False),
    ("estimators", "calibration.static", False),
    ("flight", "scenarios.tp", False),
    ("quadcosim", "findings.__main__", True),
    ("quadcosim", "findings.readme", False),
])
def test_the_rule_itself(layer, module, expected):
    assert _allowed(layer, module, _modules() | {"fmus.build", "orchestrator.system"}) is expected


# Functions written before this rule, still to be split by their owners; the list may only shrink.
LONG_PENDING: set[str] = set()
MAX_FUNCTION_LINES = 60  # code lines, the docstring not counted


def _function_lengths():
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                    first = node.body[0]
                    documented = isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) \
                        and isinstance(first.value.value, str)
                    doc = first.end_lineno - first.lineno + 1 if documented else 0
                    yield f"{path.relative_to(ROOT)}:{node.name}", node.end_lineno - node.lineno + 1 - doc


def test_no_function_is_over_sixty_lines():
    long = [f"{name} ({n} lines)" for name, n in _function_lengths()
            if n > MAX_FUNCTION_LINES and name not in LONG_PENDING]
    assert not long, "split these functions into named steps:\n" + "\n".join(long)


def test_the_master_module_stays_short():
    assert len((ROOT / "orchestrator" / "system.py").read_text().splitlines()) < 300
