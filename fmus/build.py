"""Build the plant FMUs from source with the system C compiler, in FMI 2.0 and FMI 3.0.

For each model and FMI version the build stages a source FMU: ``modelDescription.xml`` and
``variables.h`` generated from the model's variable table, ``airframe.h`` from
:mod:`quadcosim.fmus.airframe`, the shared shell, the model's equations and the FMI headers of that
version (taken from the installed fmpy); FMI 3.0 adds ``sources/buildDescription.xml``. The
binaries are then compiled from those staged sources alone, warnings as errors, so that the
sources shipped in the FMU are known to build: for Linux with the system compiler, and for
Windows with mingw-w64 when it is installed (``x86_64-w64-mingw32-gcc``, or ``$CC_WIN64``).

The FMI 2.0 FMUs are ``<out>/<Model>.fmu`` (what a run loads), the FMI 3.0 ones
``<out>/fmi3/<Model>.fmu``. One source serves both versions: ``shell.c`` is the FMI 2.0 API and
``fmi3.c`` the FMI 3.0 one, over the state machine of ``cosimulation.h``.
"""

from __future__ import annotations

import functools
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

from quadcosim.fmus import models as registry
from quadcosim.fmus.airframe import c_header as airframe_header
from quadcosim.fmus.models import fmu_sources, model_folder, model_variables

from quadcosim.infra.errors import RunError
from quadcosim.infra.folders import compiler_command, make_folder

HERE = Path(__file__).resolve().parent
CFLAGS = ["-std=c99", "-O2", "-fPIC", "-Wall", "-Wextra", "-Werror", "-fvisibility=hidden"]
FMI_VERSIONS = (2, 3)
#: The FMI headers each version's sources include.
FMI_HEADERS = {2: ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h"),
               3: ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h")}
#: The C files compiled for each version: its API (which includes the shared state machine) and the model.
SOURCE_FILES = {2: ("shell.c", "model.c"), 3: ("fmi3.c", "model.c")}
#: The shell's headers, shipped in every FMU.
SHELL_HEADERS = ("shell.h", "cosimulation.h", "quaternion.h", "noise.h")
#: The binaries folder of each platform, by FMI version (FMI 3.0 names platforms by tuple).
PLATFORMS = {2: {"linux": "linux64", "windows": "win64"}, 3: {"linux": "x86_64-linux", "windows": "x86_64-windows"}}
#: The mingw-w64 cross compiler that builds the Windows binaries (Debian: gcc-mingw-w64-x86-64).
WINDOWS_COMPILER = "x86_64-w64-mingw32-gcc"
#: Flags of each platform's link beyond CFLAGS: the Windows DLL carries libgcc's helpers (some
#: models call them) instead of needing libgcc_s_seh-1.dll beside it, and no symbol table (which
#: would make it four times larger: mingw's C library is linked in).
LINK_FLAGS = {"linux": [], "windows": ["-static-libgcc", "-s"]}


class BuildError(RunError, RuntimeError):
    """The C compiler refused a model."""


def table(model: str):
    """The variable table of ``model``.

    Parameters
    ----------
    model : str
        A registered model (:data:`quadcosim.fmus.MODELS`).

    Returns
    -------
    quadcosim.fmus.variables.Table
        The ``TABLE`` of its folder's ``variables.py``.
    """
    return model_variables(model).TABLE


def _fmi_header_dir() -> Path:
    import fmpy

    path = Path(fmpy.__file__).parent / "c-code"
    missing = [name for names in FMI_HEADERS.values() for name in names if not (path / name).exists()]
    if missing:
        raise BuildError(f"the FMI headers {', '.join(missing)} are missing from fmpy ({path}); reinstall fmpy")
    return path


def fmu_file(model: str, out_dir: Path, fmi_version: int = 2) -> Path:
    """Where the build writes ``model``'s FMU of one FMI version.

    Parameters
    ----------
    model : str
        Model name.
    out_dir : pathlib.Path
        The build's output folder.
    fmi_version : int
        2 (``out_dir/<model>.fmu``) or 3 (``out_dir/fmi3/<model>.fmu``).

    Returns
    -------
    pathlib.Path
    """
    if fmi_version not in FMI_VERSIONS:
        raise ValueError(f"FMI version {fmi_version!r}; the plant's FMUs are built in FMI 2 and 3")
    folder = Path(out_dir) if fmi_version == 2 else Path(out_dir) / "fmi3"
    return folder / f"{model}.fmu"


@functools.cache
def windows_compiler() -> str | None:
    """The mingw-w64 compiler of the Windows binaries: ``$CC_WIN64`` or ``x86_64-w64-mingw32-gcc``.

    Returns
    -------
    str or None
        Its path; None when it is not installed, said once on standard error (the FMUs are then
        built without their Windows binaries).
    """
    found = shutil.which(os.environ.get("CC_WIN64", WINDOWS_COMPILER))
    if found is None:
        print(f"quadcosim: no {os.environ.get('CC_WIN64', WINDOWS_COMPILER)} (mingw-w64; Debian: apt-get install "
              "gcc-mingw-w64-x86-64): the FMUs are built without Windows binaries", file=sys.stderr, flush=True)
    return found


def _compile(model: str, stage: Path, compiler: list, source_files: list, fmi_version: int, windows: bool) -> None:
    """Compile the staged sources of ``model`` into its binaries: Linux, and Windows when asked and
    mingw-w64 is installed, side by side."""
    sources = stage / "sources"
    targets = {"linux": (compiler, ".so")}
    mingw = windows_compiler() if windows else None
    if mingw:
        targets["windows"] = ([mingw], ".dll")
    jobs = []
    for platform, (cc, suffix) in targets.items():
        binaries = stage / "binaries" / PLATFORMS[fmi_version][platform]
        binaries.mkdir(parents=True)
        command = [*cc, *CFLAGS, *LINK_FLAGS[platform], "-shared", "-I", str(sources),
                   "-o", str(binaries / f"{model}{suffix}")]
        command += [str(sources / s) for s in source_files] + ["-lm"]
        try:
            jobs.append((command, subprocess.Popen(command, stderr=subprocess.PIPE, text=True)))
        except FileNotFoundError:
            raise BuildError(f"no C compiler {cc[0]!r} (from ${'CC' if os.environ.get('CC') else 'CC unset: cc'}); "
                             "install one (e.g. gcc) or set $CC") from None
    for command, job in jobs:  # the platforms compile side by side
        _, errors = job.communicate()
        if job.returncode != 0:
            raise BuildError(f"{model}: {' '.join(command)}\n{errors}")


def build_fmu(model: str, out_dir: Path, compiler: str | None = None, variables=None, fmi_version: int = 2,
              windows: bool = True) -> Path:
    """Build ``model``'s FMU of one FMI version from source (:func:`fmu_file` says where).

    Parameters
    ----------
    model : str
        A registered model (its folder's ``model.c``; its ``variables.py`` unless ``variables``).
    out_dir : pathlib.Path
        Output folder; the staged sources stay beside the FMU, in ``<model>/``.
    compiler : str, optional
        C compiler command; ``$CC`` or ``cc`` by default.
    variables : quadcosim.fmus.variables.Table, optional
        A variable table to build with instead of the model's own (tests build variants).
    fmi_version : int
        2 or 3.
    windows : bool
        Also compile the Windows binary, when mingw-w64 is installed (:func:`windows_compiler`).

    Returns
    -------
    pathlib.Path
        The ``.fmu`` file.

    Raises
    ------
    BuildError
        The table is inconsistent (a vector's members apart, say) or a compiler refused.
    """
    compiler = compiler_command(compiler)
    fmu = fmu_file(model, out_dir, fmi_version)
    stage = fmu.parent / model
    if stage.exists():
        shutil.rmtree(stage)
    sources = stage / "sources"
    sources.mkdir(parents=True)

    tab = variables or table(model)
    source_files = list(SOURCE_FILES[fmi_version])
    try:
        header = tab.c_header(fmi_version)
        description = tab.model_description(list(SOURCE_FILES[2]) if fmi_version == 2 else [], fmi_version)
    except ValueError as error:
        raise BuildError(str(error)) from None
    for name in FMI_HEADERS[fmi_version]:
        shutil.copy(_fmi_header_dir() / name, sources / name)
    for name in (*SHELL_HEADERS, source_files[0]):
        shutil.copy(HERE / "c" / name, sources / name)
    shutil.copy(model_folder(model) / "model.c", sources / "model.c")
    (sources / "variables.h").write_text(header)
    (sources / "airframe.h").write_text(airframe_header())
    if fmi_version == 3:
        (sources / "buildDescription.xml").write_text(tab.build_description(source_files))
    (stage / "modelDescription.xml").write_text(description)

    _compile(model, stage, compiler, source_files, fmi_version, windows)

    # written whole, then renamed (fmus sits below the orchestrator and its writer): a build cut
    # short leaves the earlier FMU, never a truncated one a run would load
    partial = fmu.parent / f".{model}.fmu.part"
    try:
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as archive:
            for path in sorted(stage.rglob("*")):
                if path.is_file():
                    archive.write(path, path.relative_to(stage).as_posix())
        os.replace(partial, fmu)
    finally:
        partial.unlink(missing_ok=True)
    return fmu


def up_to_date(model: str, out_dir: Path, fmi_version: int = 2) -> bool:
    """Whether ``model``'s FMU of one FMI version needs no rebuild.

    Parameters
    ----------
    model : str
        Model name.
    out_dir : pathlib.Path
        The build's output folder.
    fmi_version : int
        2 or 3.

    Returns
    -------
    bool
        The FMU is newer than each of its sources (:func:`quadcosim.fmus.fmu_sources`) and holds the binary of
        each platform this machine builds for (Windows only with mingw-w64).
    """
    fmu = fmu_file(model, out_dir, fmi_version)
    if not fmu.is_file() or any(s.stat().st_mtime > fmu.stat().st_mtime for s in fmu_sources(model)):
        return False
    platforms = ["linux", "windows"] if windows_compiler() else ["linux"]
    suffix = {"linux": ".so", "windows": ".dll"}
    with zipfile.ZipFile(fmu) as archive:
        names = set(archive.namelist())
    return all(f"binaries/{PLATFORMS[fmi_version][p]}/{model}{suffix[p]}" in names for p in platforms)


def build_all(out_dir: Path, models=None, verbose: bool = True, fmi_versions=FMI_VERSIONS,
              force: bool = False) -> list[Path]:
    """Build every plant FMU, in each FMI version, that is not up to date, and write the Modelica
    package of their twins beside them (:func:`quadcosim.fmus.modelica.write_package`).

    Parameters
    ----------
    out_dir : pathlib.Path
        Output folder (:func:`quadcosim.fmus.default_fmu_dir`, where a run looks for the FMUs).
    models : sequence of str, optional
        Model names; every registered one (:data:`quadcosim.fmus.MODELS`) by default.
    verbose : bool
        Print each FMU's path as it is built (or found up to date).
    fmi_versions : sequence of int
        FMI versions; 2 and 3 by default.
    force : bool
        Rebuild the FMUs that are up to date too (:func:`up_to_date`: newer than their sources,
        with every binary this machine builds), after a change of compiler say.

    Returns
    -------
    list of pathlib.Path
        The ``.fmu`` files, built or up to date.
    """
    from quadcosim.fmus.modelica import write_package

    out_dir = make_folder(out_dir, "the FMUs")
    models = registry.MODELS if models is None else tuple(models)
    built = []
    for fmi_version in fmi_versions:
        fmu_file(models[0], out_dir, fmi_version).parent.mkdir(parents=True, exist_ok=True)
        for model in models:
            if not force and up_to_date(model, out_dir, fmi_version):
                built.append(fmu_file(model, out_dir, fmi_version))
                if verbose:
                    print(f"up to date {built[-1]}")
                continue
            built.append(build_fmu(model, out_dir, fmi_version=fmi_version))
            if verbose:
                print(f"built {built[-1]}")
    package = write_package(out_dir / "QuadCoSim")
    if verbose:
        print(f"wrote {package}")
    return built
