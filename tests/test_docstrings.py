"""Every public callable of the package has a docstring, and the docstring names every
parameter (NumPy style).

The public API is listed, not sampled: every module of every package is imported, and every
function, class, method and property whose name does not start with an underscore and that
the module itself defines is checked (the way python-control's docstring test walks its
modules).
"""

import importlib
import inspect
import pkgutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("fmus", "orchestrator", "estimators", "calibration", "flight", "scenarios", "benchmarks")  # folders



def _modules():
    for package in ("quadcosim/infra", *PACKAGES):
        name = package.replace("/", ".") if "/" in package else f"quadcosim.{package}"
        yield name
        for info in pkgutil.walk_packages([str(ROOT / package)], prefix=f"{name}."):
            yield info.name


def _public(module):
    """(qualified name, object, owner class or None) of the module's public callables."""
    for name, obj in vars(module).items():
        if name.startswith("_") or getattr(obj, "__module__", None) != module.__name__:
            continue
        if inspect.isclass(obj):
            yield f"{module.__name__}.{name}", obj, None
            for member, value in vars(obj).items():
                if member.startswith("_"):
                    continue
                if isinstance(value, staticmethod | classmethod):
                    value = value.__func__
                if inspect.isfunction(value) or isinstance(value, property):
                    yield f"{module.__name__}.{name}.{member}", value, obj
        elif inspect.isfunction(obj) or hasattr(obj, "py_func"):  # numba dispatchers too
            yield f"{module.__name__}.{name}", obj, None


def _docstring(obj, owner) -> str:
    if isinstance(obj, property):
        return inspect.getdoc(obj.fget) or ""
    if owner is not None:  # an override documented on a base class counts
        return inspect.getdoc(getattr(owner, obj.__name__)) or ""
    return inspect.getdoc(obj) or ""


def _parameters(obj) -> list[str]:
    target = obj.__init__ if inspect.isclass(obj) else getattr(obj, "py_func", obj)
    if isinstance(obj, property) or target is object.__init__:
        return []
    try:
        signature = inspect.signature(target)
    except (TypeError, ValueError):
        return []
    return [p.name for p in signature.parameters.values()
            if p.name not in ("self", "cls") and not p.name.startswith("_")
            and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]


def _problems() -> list[str]:
    problems = []
    for module_name in _modules():
        module = importlib.import_module(module_name)
        for name, obj, owner in _public(module):
            text = _docstring(obj, owner)
            if not text.strip():
                problems.append(f"{name}: no docstring")
                continue
            if inspect.isclass(obj):
                text += "\n" + (inspect.getdoc(obj.__init__) or "")
            missing = [p for p in _parameters(obj) if p not in text]
            if missing:
                problems.append(f"{name}: parameters not described: {', '.join(missing)}")
    return problems


def test_the_public_api_is_listed():
    names = {name for m in _modules() for name, _, _ in _public(importlib.import_module(m))}
    # a few entries every user meets, so that a walk that finds nothing cannot pass
    assert {"quadcosim.orchestrator.system.System.run", "quadcosim.orchestrator.system.System.connect",
            "quadcosim.orchestrator.fmu.FMUInstance.step", "quadcosim.fmus.build.build_fmu"} <= names
    assert len(names) > 150


@pytest.mark.parametrize("package", PACKAGES)
def test_every_public_callable_has_a_docstring(package):
    problems = [p for p in _problems() if p.startswith(f"quadcosim.{package}.")]
    assert not problems, f"{len(problems)} public callables of {package} lack documentation:\n" + "\n".join(problems)
