"""The Modelica package ``QuadCoSim``: the twins of the registered models, gathered from their folders.

Each model's twin is the class file ``<Model>.mo`` beside its ``model.c`` (``within QuadCoSim;``);
the package's own file is ``fmus/QuadCoSim/package.mo``. :func:`package_source` nests them in one
text for the pure-Python ``modelica`` toolchain, which reads one program; :func:`write_package`
writes them as a package folder (``package.mo``, the class files, ``package.order``) that
OpenModelica and Dymola load (``quadcosim build`` writes it beside the FMUs).
"""

from __future__ import annotations

import re
from pathlib import Path

from quadcosim.fmus.models import sensors

PACKAGE = Path(__file__).resolve().parent / "QuadCoSim" / "package.mo"


def twins() -> dict[str, Path]:
    """The twin of each registered model that has one, by model name."""
    return {name: member.twin for name, member in sensors().items() if member.twin is not None}


def package_source() -> str:
    """The QuadCoSim package as one Modelica text, the twins' classes nested in ``package.mo``.

    Returns
    -------
    str
        The package, as the ``modelica`` toolchain reads a single program.
    """
    package = re.sub(r"^\s*within\s*;", "", PACKAGE.read_text(), count=1)
    body = [re.sub(r"^\s*within\s+[\w.]*\s*;", "", path.read_text(), count=1) for path in twins().values()]
    end = package.rindex("end QuadCoSim;")
    return package[:end] + "\n".join(body) + "\n" + package[end:]


def write_package(folder: Path) -> Path:
    """Write the package folder ``QuadCoSim``: ``package.mo``, each twin's class file and the
    ``package.order`` of the registry; files unchanged are left alone, stale class files removed.

    Parameters
    ----------
    folder : pathlib.Path
        The package folder to write (named ``QuadCoSim``).

    Returns
    -------
    pathlib.Path
        Its ``package.mo``.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    found = twins()
    files = {"package.mo": PACKAGE.read_text(), "package.order": "".join(f"{name}\n" for name in found)}
    files |= {f"{name}.mo": path.read_text() for name, path in found.items()}
    for stale in folder.glob("*.mo"):
        if stale.name not in files:
            stale.unlink()
    for name, text in files.items():
        target = folder / name
        if not target.is_file() or target.read_text() != text:
            target.write_text(text)
    return folder / "package.mo"
