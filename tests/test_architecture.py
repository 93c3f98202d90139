"""Dependencies point one way, floor by floor: each package imports only from the floors below
it (:data:`FLOORS`), and the lower packages only the modules their rule names (:data:`ALLOWED`).

Every import in every module of the project is read from its syntax tree (imports inside
functions included), so a late import cannot hide a dependency; so is every module loaded by
name (``importlib.import_module``, ``__import__``): a literal name is an import like any other, a
name with a computed tail is an import of the package its literal head names, and a name computed
whole is allowed only where :data:`LOADS_BY_NAME` says what it loads. Besides the floors: no
circle of imports between the modules of one package, the FMUs' C sources include only what
their part of the shell/model split may (:data:`C_INCLUDES`), and no module is longer than
:data:`MAX_MODULE_LINES`.
"""

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: The floors, from the ground up, by import name and folder: the infrastructure every floor
#: may use (files, interrupts, progress, caches), the plant, the master, reading flight logs,
#: estimation and calibration, flight control, the scenarios, the studies over many runs, the
#: benchmarks, the package's own face (its Python API and command line), and the maintainer's
#: findings (not shipped).
FLOORS = ("quadcosim.infra", "quadcosim.fmus", "quadcosim.orchestrator", "quadcosim.flightlogs",
          "quadcosim.estimators", "quadcosim.calibration", "quadcosim.flight", "quadcosim.scenarios",
          "quadcosim.studies", "quadcosim.benchmarks", "quadcosim", "findings")
#: Where each floor's sources are: the repository's folders are installed as ``quadcosim.<folder>``.
FOLDERS = {"quadcosim.infra": "quadcosim/infra", "quadcosim": "quadcosim", "findings": "findings",
           **{floor: floor.split(".")[1] for floor in FLOORS[1:-2]}}
#: The import names of the project: anything else is a library, or the user's own.
PACKAGES = ("quadcosim", "findings")
#: The folders' own names, which a user's project may hold too: never imported bare.
FOLDER_NAMES = tuple(name for name in FOLDERS.values() if "/" not in name and name not in PACKAGES)


def _floor(module: str) -> str:
    """The floor a module name is on: the longest floor name it is or starts with."""
    return max((f for f in FLOORS if module == f or module.startswith(f + ".")), key=len, default="")


def _below(package: str) -> tuple[str, ...]:
    """Every package on a floor below ``package``'s, as whole-package rules."""
    return tuple(f"{p}." for p in FLOORS[:FLOORS.index(package)])


GROUND = "quadcosim.infra."
# What each package may import from the project, besides itself. A name ending in "." allows
# the whole package; a bare module name allows that module and nothing below it. No package is
# allowed a floor above its own.
ALLOWED = {
    "quadcosim.infra": (),
    "quadcosim.fmus": (GROUND,),
    # to find built FMUs only: the package's locating functions, not its build or its models
    "quadcosim.orchestrator": (GROUND, "quadcosim.fmus"),
    "quadcosim.flightlogs": (GROUND,),
    # the block contract, the plant's constants and the flight-log reading layer
    "quadcosim.estimators": (GROUND, "quadcosim.orchestrator.blocks", "quadcosim.flightlogs.", "quadcosim.fmus."),
    "quadcosim.calibration": (GROUND, "quadcosim.orchestrator.blocks", "quadcosim.flightlogs.", "quadcosim.fmus."),
    # the controller: the block contract, the plant, the estimators' quaternion arithmetic
    "quadcosim.flight": (GROUND, "quadcosim.fmus.", "quadcosim.orchestrator.", "quadcosim.estimators."),
    "quadcosim.scenarios": _below("quadcosim.scenarios"),
    "quadcosim.studies": _below("quadcosim.studies"),
    "quadcosim.benchmarks": _below("quadcosim.benchmarks"),
    "quadcosim": _below("quadcosim"),
    "findings": _below("findings"),
}

#: The places that load a module whose name is computed whole, and what that name is: the
#: floors are checked where the name is written (a user's file, or a registration of a package
#: that may import the module, :func:`test_every_registered_member_is_a_module_of_the_project`).
LOADS_BY_NAME = {
    "estimators/contract.py": "a block class of the user's, named module:Class on the command line",
    "studies/sweep/engine.py": "a metric function of the user's, named module:function in a sweep file",
    "quadcosim/infra/members.py": "a member of a closed set, as its entry point (pyproject.toml) names it",
    "quadcosim/__init__.py": "the subpackage holding a name of the Python API, as its _EXPORTS table says",
}

_LOADERS = {"import_module", "__import__"}
COMPUTED = "*"  # the computed part of a module name loaded by name


def _load_name(call: ast.Call) -> str | None:
    """The module a call to ``import_module``/``__import__`` loads: its name, its literal head
    followed by :data:`COMPUTED` (an f-string), or :data:`COMPUTED` (a name computed whole);
    None for a call of something else."""
    function = call.func
    called = function.attr if isinstance(function, ast.Attribute) else getattr(function, "id", None)
    if called not in _LOADERS or not call.args:
        return None
    name = call.args[0]
    if isinstance(name, ast.Constant) and isinstance(name.value, str):
        return name.value
    if isinstance(name, ast.JoinedStr):
        head = ""
        for part in name.values:
            if not isinstance(part, ast.Constant):
                break
            head += part.value
        return head + COMPUTED
    return COMPUTED


def _imports(path: Path) -> list[tuple[int, str]]:
    """(line, absolute module name) of every import and load by name of a project package in
    ``path``; a name computed whole is :data:`COMPUTED`."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                raise AssertionError(f"{path.relative_to(ROOT)}:{node.lineno}: relative import; write it absolute")
            # `from fmus import vehicle` imports the module quadcosim.fmus.vehicle; `from fmus import fmu_path`
            # an attribute of fmus, told apart where the name is checked
            found += [(node.lineno, f"{node.module}.{alias.name}") for alias in node.names]
        elif isinstance(node, ast.Call) and (loaded := _load_name(node)) is not None:
            found.append((node.lineno, loaded))
    return [(line, name) for line, name in found
            if name == COMPUTED or name.split(".")[0].rstrip(COMPUTED) in PACKAGES + FOLDER_NAMES]


def _allowed(layer: str, module: str, package_names: set[str]) -> bool:
    if _floor(module.rstrip(COMPUTED).rstrip(".")) == layer:
        return True
    computed = module.endswith(COMPUTED)  # any module below its literal head: a whole-package rule only
    head = module.rstrip(COMPUTED).rstrip(".")
    for rule in ALLOWED[layer]:
        if rule.endswith(".") and (head + ".").startswith(rule):
            return True
        if computed:
            continue
        # `from fmus import fmu_path` names an attribute of the package, not a module
        if module == rule or (module.rsplit(".", 1)[0] == rule and module not in package_names):
            return True
    return False


def _floor_of(path: Path) -> str:
    """The floor whose folder holds ``path`` (the most specific folder)."""
    where = path.relative_to(ROOT).as_posix()
    return max((f for f, folder in FOLDERS.items() if where.startswith(folder + "/")),
               key=lambda f: len(FOLDERS[f]))


def _sources(suffix: str = ".py"):
    for floor in FLOORS:
        yield from sorted(p for p in (ROOT / FOLDERS[floor]).rglob(f"*{suffix}") if _floor_of(p) == floor)


def _module_of(path: Path) -> str:
    floor = _floor_of(path)
    parts = path.relative_to(ROOT / FOLDERS[floor]).with_suffix("").parts
    parts = floor.split(".") + list(parts[:-1] if parts[-1] == "__init__" else parts)
    return ".".join(parts)


def _modules() -> set[str]:
    return {_module_of(path) for path in _sources()}


def _violations() -> list[str]:
    modules = _modules()
    bad = []
    for path in _sources():
        where = path.relative_to(ROOT)
        package = _floor_of(path)
        for line, module in _imports(path):
            if module.split(".")[0] in FOLDER_NAMES:
                bad.append(f"{where}:{line} imports {module.split('.')[0]} bare: a user's package of that name "
                           f"would be imported; write quadcosim.{module}")
            elif module == COMPUTED:
                if where.as_posix() not in LOADS_BY_NAME:
                    bad.append(f"{where}:{line} loads a module by a name computed whole; name it, or declare "
                               "the place in LOADS_BY_NAME with what it loads")
            elif not _allowed(package, module, modules):
                shown = module  # the module, not the attribute taken from it
                while shown not in modules and "." in shown and not shown.endswith(COMPUTED):
                    shown = shown.rsplit(".", 1)[0]
                bad.append(f"{where}:{line} {'loads' if module.endswith(COMPUTED) else 'imports'} {shown}")
    return bad


def test_every_import_points_down_the_layers():
    bad = _violations()
    assert not bad, f"imports against the floors {' <- '.join(FLOORS)}:\n" + "\n".join(bad)


def test_the_places_that_load_by_name_exist():
    assert [p for p in LOADS_BY_NAME if not (ROOT / p).is_file()] == []


def test_every_registered_member_is_a_module_of_the_project():
    """A member is loaded by the name its entry point gives (pyproject.toml): that module exists,
    and a member of a set sits on or above the floor of the package reading that set."""
    import tomllib

    from quadcosim.infra.members import GROUPS

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["entry-points"]
    modules = _modules()
    readers = {"scenarios": "quadcosim.scenarios", "estimators": "quadcosim.estimators",
               "sensors": "quadcosim.fmus", "autopilots": "quadcosim.flightlogs",
               "interference": "quadcosim.calibration"}
    bad = []
    for kind, group in GROUPS.items():
        for name, value in project.get(group, {}).items():
            module = value.split(":")[0]
            if module not in modules:
                bad.append(f"{group} {name}: {module} is not a module of the project")
            elif FLOORS.index(_floor(module)) < FLOORS.index(readers[kind]):
                bad.append(f"{group} {name}: {module} is below {readers[kind]}, which reads the set")
    assert project.get(GROUPS["scenarios"]), "no scenario registered"
    assert not bad, "\n".join(bad)


def _edges() -> dict[str, set[str]]:
    """Each module's imports of modules of its own package (the package's ``__init__`` counts
    as a module); a load by a computed name is no edge (it loads a member of a registry)."""
    modules = _modules()
    edges = {}
    for path in _sources():
        source = _module_of(path)
        targets = set()
        for _, name in _imports(path):
            if name.endswith(COMPUTED) or _floor(name) != _floor(source):
                continue
            while name not in modules:  # an attribute of a module: that module
                name = name.rsplit(".", 1)[0]
            if name != source:
                targets.add(name)
        edges[source] = targets
    return edges


def _circles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(node):
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for target in sorted(edges.get(node, ())):
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(edges):
        if node not in index:
            visit(node)
    return found


def test_no_circle_of_imports_inside_a_package():
    circles = _circles(_edges())
    assert not circles, "modules that import each other (move what both need to a module of its own):\n" + \
        "\n".join(" <-> ".join(c) for c in circles)


def test_the_circle_finder_itself():
    assert _circles({"a.x": {"a.y"}, "a.y": {"a.z"}, "a.z": {"a.x"}, "a.w": {"a.x"}}) == [["a.x", "a.y", "a.z"]]
    assert _circles({"a.x": {"a.y"}, "a.y": set()}) == []


def test_the_command_line_and_the_benchmarks_live_in_the_top_layer():
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert project["project"]["scripts"]["quadcosim"] == "quadcosim.cli:entry"
    assert "quadcosim.benchmarks" in project["tool"]["setuptools"]["packages"]
    assert not (ROOT / "orchestrator" / "cli.py").exists()
    assert not list((ROOT / "orchestrator").glob("bench*.py"))
    assert not list((ROOT / "estimators").glob("bench*.py"))


@pytest.mark.parametrize(("layer", "module", "expected"), [
    ("orchestrator", "fmus", True),
    ("orchestrator", "fmus.fmu_path", True),
    ("orchestrator", "fmus.build", False),
    ("orchestrator", "scenarios", False),
    ("orchestrator", "fmus.*", False),  # fmus.<Model>.variables by a computed name
    ("orchestrator", "infra.files", True),
    ("fmus", "orchestrator.fmu", False),
    ("infra", "fmus", False),
    ("estimators", "orchestrator.blocks", True),
    ("estimators", "orchestrator.system", False),
    ("calibration", "flightlogs.model", True),
    ("calibration", "orchestrator.fmu", False),
    ("estimators", "scenarios.plant", False),
    ("scenarios", "benchmarks.master", False),
    ("benchmarks", "scenarios.tp", True),
    ("scenarios", "studies.sweep", False),
    ("scenarios", "studies.*", False),
    ("studies", "studies.*", True),
    ("", "studies.*", True),  # the package's face over the studies
    ("flightlogs", "infra.files", True),
    ("flightlogs", "calibration.static", False),
    ("estimators", "calibration.static", False),
    ("flight", "scenarios.tp", False),
    ("", "main", True),
    ("benchmarks", "main", False),
])
def test_the_rule_itself(layer, module, expected):
    """Floors and modules named without their ``quadcosim.`` (``""``: the package's face)."""
    layer = f"quadcosim.{layer}".rstrip(".")
    assert _allowed(layer, f"quadcosim.{module}", _modules() | {"quadcosim.fmus.build",
                                                                "quadcosim.orchestrator.system"}) is expected


@pytest.mark.parametrize(("source", "loaded"), [
    ("importlib.import_module('quadcosim.benchmarks.master')", "quadcosim.benchmarks.master"),
    ("import_module(f'quadcosim.studies.{name}')", "quadcosim.studies.*"),
    ("__import__(name)", COMPUTED),
    ("importlib.util.find_spec(name)", None),
])
def test_loads_by_name_are_seen(source, loaded):
    assert _load_name(ast.parse(source).body[0].value) == loaded


# --- the FMUs' C sources: the Reference-FMUs-like split of one shell and many models ----------

#: Headers the build writes into an FMU's sources (fmus/build.py): generated per model
#: (``variables.h``, which includes ``shell.h``; ``airframe.h``), or the FMI standard's.
GENERATED_HEADERS = {"variables.h", "airframe.h"}
FMI_HEADERS = {"fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h",
               "fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h"}
#: The C standard library, the only angle-bracket headers an FMU may include (it links nothing else).
C_STANDARD = {"complex.h", "float.h", "math.h", "stdarg.h", "stdbool.h", "stddef.h", "stdint.h", "stdio.h",
              "stdlib.h", "string.h"}
#: What each part of an FMU's C sources may include in quotes. The shell (the FMI state machine
#: in ``cosimulation.h``, one for every model, under the FMI 2.0 API ``shell.c`` or the FMI 3.0 API
#: ``fmi3.c``) knows a model only by its generated variable table; a model
#: (``fmus/<Model>/model.c``) sees the shell through that table and the shared numerical helpers,
#: never the FMI API itself nor another model; the helpers include nothing of the project.
C_INCLUDES = {
    "shell.c": {"cosimulation.h"},
    "fmi3.c": {"cosimulation.h"},
    "cosimulation.h": {"variables.h"},
    "shell.h": {"fmi2Functions.h", "fmi3Functions.h"},
    "helper": set(),
    "model.c": {"variables.h", "airframe.h", "quaternion.h", "noise.h"},
}


def _c_part(path: Path) -> str:
    if path.parent.name == "c":
        return path.name if path.name in ("shell.c", "fmi3.c", "cosimulation.h", "shell.h") else "helper"
    assert path.name == "model.c", f"{path.relative_to(ROOT)}: a model's C source is its model.c alone"
    return "model.c"


def _c_includes(path: Path) -> list[tuple[str, str]]:
    """(``"<"`` or ``'"'``, name) of every ``#include`` of ``path``."""
    return re.findall(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]', path.read_text(), re.MULTILINE)


def test_the_fmus_c_sources_include_only_what_their_part_may():
    bad = []
    shared = {p.name for p in (ROOT / "fmus" / "c").glob("*.h")}
    # the package's FMUs and the registry's dummy sensor FMU (tests/registry_dummies/), held to the same rules
    for path in sorted([*(ROOT / "fmus").rglob("*.[ch]"), *(ROOT / "tests" / "registry_dummies").rglob("*.[ch]")]):
        part, where = _c_part(path), path.relative_to(ROOT)
        for bracket, name in _c_includes(path):
            if bracket == "<" and name not in C_STANDARD:
                bad.append(f"{where} includes <{name}>: an FMU links the C standard library alone")
            elif bracket == '"' and name not in C_INCLUDES[part]:
                bad.append(f'{where} includes "{name}": its part ({part}) may include {sorted(C_INCLUDES[part])}')
            elif bracket == '"' and name not in shared | GENERATED_HEADERS | FMI_HEADERS:
                bad.append(f'{where} includes "{name}", which neither fmus/c/ holds nor the build writes')
    assert not bad, "\n".join(bad)


def test_the_build_ships_every_header_a_source_includes():
    """The headers of fmus/c/ the models include are the ones the build copies into an FMU."""
    build = (ROOT / "fmus" / "build.py").read_text()
    included = set().union(*C_INCLUDES.values()) - GENERATED_HEADERS - FMI_HEADERS
    assert [h for h in sorted(included) if f'"{h}"' not in build] == []


# --- numba's cache ---------------------------------------------------------------------------


def _caches_numba_code(tree: ast.Module) -> int | None:
    """First line of a ``cache=True`` keyword (a numba decorator's) in the module, or None."""
    lines = [node.value.lineno for node in ast.walk(tree) if isinstance(node, ast.keyword) and node.arg == "cache"
             and isinstance(node.value, ast.Constant) and node.value.value is True]
    return min(lines, default=None)


def _install_line(tree: ast.Module) -> int | None:
    """Line of the module's top-level ``numba_cache.install()``, or None."""
    for node in tree.body:
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Call) and \
                ast.unparse(node.value.func) == "numba_cache.install":
            return node.lineno
    return None


def _package_installs_first(init: Path) -> bool:
    """The package's ``__init__`` installs numba_cache's locator before it imports its own modules."""
    tree = ast.parse(init.read_text())
    package = _module_of(init)
    own = [node.lineno for node in tree.body if isinstance(node, ast.ImportFrom)
           and (node.module or "").startswith(package + ".")]
    line = _install_line(tree)
    return line is not None and line < min(own, default=line + 1)


def test_cached_numba_code_is_keyed_by_its_sources():
    """numba picks a function's cache folder when it decorates it: a module holding cached numba
    code installs :mod:`quadcosim.infra.numba_cache`'s locator before its first decorator, or a
    package it is in does before importing its modules; and it is on a floor the key covers."""
    from quadcosim.infra import numba_cache

    assert numba_cache.FLOORS == tuple(FOLDERS[f] for f in FLOORS[1:1 + len(numba_cache.FLOORS)])
    bad = []
    for path in _sources():
        tree = ast.parse(path.read_text())
        first = _caches_numba_code(tree)
        if first is None:
            continue
        where = path.relative_to(ROOT)
        if where.parts[0] not in numba_cache.FLOORS:  # the floors' folders
            bad.append(f"{where}: above the floors numba_cache.FLOORS keys")
        own = _install_line(tree)
        packages = [ROOT.joinpath(*where.parts[:k], "__init__.py") for k in range(1, len(where.parts))]
        if not (own is not None and own < first) and not any(_package_installs_first(p) for p in packages):
            bad.append(f"{where}:{first} caches numba code with no numba_cache.install() before it")
    assert not bad, "\n".join(bad)


# --- sizes ----------------------------------------------------------------------------------

MAX_FUNCTION_LINES = 60  # code lines, the docstring not counted
#: Lines of a module (Python or C), docstrings and comments included: a file a reader takes in whole.
MAX_MODULE_LINES = 700  # no module is exempt


def _lengths():
    for suffix in (".py", ".c", ".h"):
        for path in _sources(suffix):
            yield path.relative_to(ROOT).as_posix(), len(path.read_text().splitlines())


def test_no_module_is_over_the_cap():
    lengths = dict(_lengths())
    long = [f"{name} ({n} lines)" for name, n in lengths.items() if n > MAX_MODULE_LINES]
    assert not long, f"over {MAX_MODULE_LINES} lines: split by concern:\n" + "\n".join(long)


def _function_lengths():
    for path in _sources():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                first = node.body[0]
                documented = isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) \
                    and isinstance(first.value.value, str)
                doc = first.end_lineno - first.lineno + 1 if documented else 0
                yield f"{path.relative_to(ROOT)}:{node.name}", node.end_lineno - node.lineno + 1 - doc


def test_no_function_is_over_sixty_lines():
    long = [f"{name} ({n} lines)" for name, n in _function_lengths()
            if n > MAX_FUNCTION_LINES]
    assert not long, "split these functions into named steps:\n" + "\n".join(long)


def test_the_master_module_stays_short():
    assert len((ROOT / "orchestrator" / "system.py").read_text().splitlines()) < 300
