"""The package as a user installs it: a wheel built from this checkout (through its sdist),
installed into a fresh virtual environment outside the checkout, runs a short scenario from an
unrelated folder, builds its FMUs and numba's cache into the per-user cache (never into
``site-packages``) and compiles the benchmark's C references from the sources it ships.

The environment is made with ``uv`` (a pinned development dependency) so that the install takes
seconds; its dependencies are resolved from ``pyproject.toml`` with the development
environment's versions as constraints, so that the test measures the package, not a new release
of a dependency.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: One import name: the repository's folders are its subpackages (findings/, a maintainer tool of
#: the checkout, is not shipped).
TOP_LEVEL = {"quadcosim"}
FOLDERS = ("fmus", "flightlogs", "orchestrator", "estimators", "calibration", "flight", "scenarios", "studies",
           "benchmarks")

pytestmark = pytest.mark.slow


def _uv() -> str:
    uv = pytest.importorskip("uv", reason="uv (a development dependency) installs the fresh environment")
    return uv.find_uv_bin()


def _clean_env(cache: Path) -> dict:
    """The process environment less anything pointing at this checkout or its environment."""
    dropped = ("VIRTUAL_ENV", "PYTHONPATH", "PYTHONHOME", "NUMBA_CACHE_DIR")
    env = {k: v for k, v in os.environ.items() if not k.startswith("QUADCOSIM_") and k not in dropped}
    env.update(XDG_CACHE_HOME=str(cache), UV_PYTHON_DOWNLOADS="never", MPLBACKEND="Agg")
    return env


def _call(command, cwd, env, timeout=600):
    done = subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
    assert done.returncode == 0, f"{' '.join(map(str, command))} exited {done.returncode}:\n{done.stderr[-3000:]}"
    return done


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(python of the fresh environment, its site-packages, the user's cache, the environment)."""
    uv = _uv()
    work = tmp_path_factory.mktemp("install")
    env = _clean_env(work / "cache")
    base = getattr(sys, "_base_executable", sys.executable)
    _call([uv, "build", "-q", "--python", base, "--out-dir", str(work / "dist"), str(ROOT)], work, env)
    wheel = next((work / "dist").glob("quadcosim-*.whl"))
    frozen = _call([uv, "pip", "freeze", "--python", sys.executable, "--exclude-editable"], work, env).stdout
    constraints = work / "constraints.txt"
    constraints.write_text("\n".join(line for line in frozen.splitlines() if not line.startswith("quadcosim")))
    venv = work / "venv"
    _call([uv, "venv", "-q", "--python", base, str(venv)], work, env)
    python = venv / "bin" / "python"
    _call([uv, "pip", "install", "-q", "--python", str(python), "-c", str(constraints), str(wheel)], work, env)
    site = Path(_call([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                      work, env).stdout.strip())
    return python, site, work / "cache", env


def test_the_wheel_holds_the_project_packages_and_their_c_sources(installed):
    _, site, _, _ = installed
    assert "build" not in {p.name for p in site.iterdir()}
    record = next(site.glob("quadcosim-*.dist-info"))
    assert (record / "licenses" / "LICENSE").read_text().startswith("MIT License")
    files = [line.split(",")[0] for line in (record / "RECORD").read_text().splitlines()]
    top = {name.split("/")[0] for name in files if not name.startswith("..")} - {record.name}
    assert top == TOP_LEVEL, top  # no `build`, no `tests`, nothing else at the top level
    for source in ("benchmarks/c/loops.c", "benchmarks/c/rotation.h", "orchestrator/c/calls.c",
                   "fmus/c/shell.c", "fmus/Quadrotor/model.c", "fmus/Quadrotor/Quadrotor.mo",
                   "fmus/QuadCoSim/package.mo"):
        assert (site / "quadcosim" / source).is_file(), source
    # every package of the checkout is shipped (pyproject.toml lists them one by one)
    inits = [init.parent.relative_to(ROOT).as_posix() for folder in (*FOLDERS, "quadcosim")
             for init in (ROOT / folder).rglob("__init__.py")]
    checkout = {name if name.startswith("quadcosim") else f"quadcosim/{name}" for name in inits}
    shipped = {str(Path(name).parent) for name in files if name.endswith("/__init__.py")}
    assert shipped == checkout, sorted(shipped ^ checkout)


def test_no_shipped_command_traces_back(installed, tmp_path):
    """Every verb's help from the installed copy, and the maintainer's `findings` (not shipped) refused
    as an unknown verb, not a ModuleNotFoundError."""
    python, _, _, env = installed
    quadcosim = python.parent / "quadcosim"
    verbs = _call([str(python), "-c", "from quadcosim.main import parser; "
                   "print(*parser()._subparsers._group_actions[0].choices)"], tmp_path, env).stdout.split()
    assert "run" in verbs and "findings" not in verbs
    for verb in verbs:
        done = subprocess.run([str(quadcosim), verb, "--help"], cwd=tmp_path, env=env, capture_output=True,
                              text=True, timeout=120)
        assert done.returncode == 0 and "Traceback" not in done.stderr, (verb, done.stderr[-2000:])
    done = subprocess.run([str(quadcosim), "findings", "--help"], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 2 and "invalid choice: 'findings'" in done.stderr and "Traceback" not in done.stderr


def test_quadcosim_run_tp_from_an_unrelated_folder(installed, tmp_path):
    python, site, cache, env = installed
    quadcosim = python.parent / "quadcosim"
    located = _call([str(python), "-c", "import quadcosim.fmus as fmus, quadcosim.scenarios; print(fmus.__file__); "
                     "print(fmus.build_root())"],
                    tmp_path, env).stdout.split()
    assert Path(located[0]).is_relative_to(site)
    assert Path(located[1]) == cache / "quadcosim" / "0.1.0"
    done = _call([str(quadcosim), "run", "tp", "--set", "duration=2"], tmp_path, env)
    metrics = json.loads((tmp_path / "results" / "tp" / "metrics.json").read_text())
    assert metrics["status"] == "completed" and metrics["samples"] == 2001
    assert all(0 < e < 0.2 for e in metrics["rms_error_deg"]), metrics["rms_error_deg"]
    assert "building the FMU Quadrotor" in done.stderr
    built = {p.name for p in (cache / "quadcosim" / "0.1.0" / "fmus").glob("*.fmu")}
    assert {"Quadrotor.fmu", "MotorMagnetics.fmu", "IMU.fmu"} <= built
    assert not (site / "build").exists()
    # numba's cache of the package's code: in the user's cache, keyed by the sources, none in site-packages
    compiled = {p.name.split("-")[0] for p in (cache / "quadcosim" / "0.1.0" / "numba").iterdir()}
    assert {"estimators", "flight"} <= compiled
    assert not list(site.rglob("*.nbi"))


def test_the_benchmark_references_compile_from_the_installed_sources(installed, tmp_path):
    python, _, cache, env = installed
    script = "from quadcosim.benchmarks import reference_library; print(reference_library('loops')._name)"
    library = Path(_call([str(python), "-c", script], tmp_path, env).stdout.strip())
    assert library == cache / "quadcosim" / "0.1.0" / "benchmarks" / "libloops.so" and library.is_file()
