"""Build the plant FMUs from source with the system C compiler.

For each model the build stages a source FMU: ``modelDescription.xml`` and ``variables.h``
generated from the model's variable table, ``airframe.h`` from :mod:`fmus.airframe`, the shared
shell, the model's equations and the FMI 2.0 headers (taken from the installed fmpy). The
shared library is then compiled from those staged sources alone, warnings as errors, so
that the sources shipped in the FMU are known to build.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import zipfile
from pathlib import Path

from fmus.airframe import c_header as airframe_header
from fmus.folders import compiler_command, make_folder
from fmus.models import MODELS, model_variables

HERE = Path(__file__).resolve().parent
CFLAGS = ["-std=c99", "-O2", "-fPIC", "-Wall", "-Wextra", "-Werror", "-fvisibility=hidden"]
FMI_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")
SOURCE_FILES = ("shell.c", "model.c")


class BuildError(RuntimeError):
    """The C compiler refused a model."""


def table(model: str):
    """The variable table of ``model``.

    Parameters
    ----------
    model : str
        Model folder under ``fmus/``.

    Returns
    -------
    fmus.variables.Table
        ``fmus.<model>.variables.TABLE``.
    """
    return model_variables(model).TABLE


def _fmi_header_dir() -> Path:
    import fmpy

    path = Path(fmpy.__file__).parent / "c-code"
    if not (path / FMI_HEADERS[0]).exists():
        raise BuildError(f"the FMI 2.0 headers are missing from fmpy ({path}); reinstall fmpy")
    return path


def build_fmu(model: str, out_dir: Path, compiler: str | None = None, variables=None) -> Path:
    """Build ``out_dir/<model>.fmu`` from source.

    Parameters
    ----------
    model : str
        Model folder under ``fmus/`` (its ``model.c``; its ``variables.py`` unless ``variables``).
    out_dir : pathlib.Path
        Output folder; the staged sources stay in ``out_dir/<model>/``.
    compiler : str, optional
        C compiler command; ``$CC`` or ``cc`` by default.
    variables : fmus.variables.Table, optional
        A variable table to build with instead of the model's own (tests build variants).

    Returns
    -------
    pathlib.Path
        The ``.fmu`` file.

    Raises
    ------
    BuildError
        The table is inconsistent (a vector's members apart, say) or the compiler refused.
    """
    compiler = compiler_command(compiler)
    stage = out_dir / model
    if stage.exists():
        shutil.rmtree(stage)
    sources = stage / "sources"
    binaries = stage / "binaries" / "linux64"
    sources.mkdir(parents=True)
    binaries.mkdir(parents=True)

    tab = variables or table(model)
    try:
        header, description = tab.c_header(), tab.model_description(list(SOURCE_FILES))
    except ValueError as error:
        raise BuildError(str(error)) from None
    for name in FMI_HEADERS:
        shutil.copy(_fmi_header_dir() / name, sources / name)
    shutil.copy(HERE / "c" / "shell.c", sources / "shell.c")
    shutil.copy(HERE / "c" / "shell.h", sources / "shell.h")
    shutil.copy(HERE / "c" / "quaternion.h", sources / "quaternion.h")
    shutil.copy(HERE / "c" / "noise.h", sources / "noise.h")
    shutil.copy(HERE / model / "model.c", sources / "model.c")
    (sources / "variables.h").write_text(header)
    (sources / "airframe.h").write_text(airframe_header())
    (stage / "modelDescription.xml").write_text(description)

    library = binaries / f"{model}.so"
    command = [*compiler, *CFLAGS, "-shared", "-I", str(sources), "-o", str(library)]
    command += [str(sources / s) for s in SOURCE_FILES] + ["-lm"]
    try:
        done = subprocess.run(command, capture_output=True, text=True)
    except FileNotFoundError:
        raise BuildError(f"no C compiler {compiler[0]!r} (from ${'CC' if os.environ.get('CC') else 'CC unset: cc'}); "
                         "install one (e.g. gcc) or set $CC") from None
    if done.returncode != 0:
        raise BuildError(f"{model}: {' '.join(command)}\n{done.stderr}")

    # written whole, then renamed (fmus sits below the orchestrator and its writer): a build cut
    # short leaves the earlier FMU, never a truncated one a run would load
    fmu = out_dir / f"{model}.fmu"
    partial = out_dir / f".{model}.fmu.part"
    try:
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as archive:
            for path in sorted(stage.rglob("*")):
                if path.is_file():
                    archive.write(path, path.relative_to(stage).as_posix())
        os.replace(partial, fmu)
    finally:
        partial.unlink(missing_ok=True)
    return fmu


def build_all(out_dir: Path, models=MODELS, verbose: bool = True) -> list[Path]:
    """Build every plant FMU.

    Parameters
    ----------
    out_dir : pathlib.Path
        Output folder (:func:`fmus.default_fmu_dir`, where a run looks for the FMUs).
    models : sequence of str
        Model names (folders under ``fmus/``); all of :data:`fmus.MODELS` by default.
    verbose : bool
        Print each FMU's path as it is built.

    Returns
    -------
    list of pathlib.Path
        The ``.fmu`` files.
    """
    out_dir = make_folder(out_dir, "the FMUs")
    built = []
    for model in models:
        built.append(build_fmu(model, out_dir))
        if verbose:
            print(f"built {built[-1]}")
    return built

