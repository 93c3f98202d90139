"""The plant's FMUs in FMI 2.0 and 3.0, for Linux and Windows: all eight validate, the FMI 3.0 ones
run in fmpy equal to the FMI 2.0 ones, and the Windows binaries, stepped under Wine by a C driver
(``tests/fmu_driver.c``), give the Linux binaries' outputs bit for bit."""

import os
import shutil
import subprocess
import zipfile
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy.validation import validate_fmu
from quadcosim.fmus import MODELS, fmu_path
from quadcosim.fmus.build import PLATFORMS, SOURCE_FILES, table, windows_compiler
from quadcosim.fmus.models import sensor

HERE = Path(__file__).resolve().parent
VERSIONS = (2, 3)


def inputs_of(model: str) -> dict:
    """Constant inputs that move the model's outputs: its ``HELD_INPUTS`` (its folder's
    ``__init__.py``; for the plant, a tilted, turning body with the rotors unequal)."""
    return sensor(model).check("HELD_INPUTS")


STEP = 1e-3
STEPS = 200  # 0.2 s: the IMU's 200 samples (and 20 of the magnetometer), MotorMagnetics' spin-up


def _outputs(description) -> list:
    return [v for v in description.modelVariables if v.causality == "output"]


def _values(variables) -> int:
    """How many values the variables hold (an FMI 3.0 array holds several)."""
    return sum(int(np.prod(v.shape)) if v.shape else 1 for v in variables)


def _column(result, name: str, model: str) -> np.ndarray:
    """Output ``name`` (an FMI 2.0 scalar) of an fmpy result, from its array in FMI 3.0."""
    if name in result.dtype.names:
        return result[name]
    for array, members in table(model).array_members().items():
        names = [v.name for v in members]
        if name in names:
            return result[array][:, names.index(name)]
    raise KeyError(name)


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("model", MODELS)
def test_validates_with_both_platforms_and_its_sources(model, version):
    path = fmu_path(model, fmi_version=version)
    assert validate_fmu(str(path)) == []
    description = fmpy.read_model_description(str(path))
    assert description.fmiVersion == f"{version}.0"
    with zipfile.ZipFile(path) as archive:
        names = set(archive.namelist())
    assert f"binaries/{PLATFORMS[version]['linux']}/{model}.so" in names
    if windows_compiler():
        assert f"binaries/{PLATFORMS[version]['windows']}/{model}.dll" in names
    assert {f"sources/{name}" for name in SOURCE_FILES[version]} <= names
    if version == 3:
        assert "sources/buildDescription.xml" in names
        arrays = {v.name: v.shape for v in description.modelVariables if v.shape}
        # the arrays its table declares (the IMU's acc, gyro, magneto), each of its members' count
        assert arrays == {name: (len(members),) for name, members in table(model).array_members().items()}
        assert [s.sourceFiles for c in description.buildConfigurations for s in c.sourceFileSets] == [
            list(SOURCE_FILES[3])]


def test_the_fmi3_binaries_export_every_function_of_the_standard(tmp_path):
    """Those of Model Exchange and Scheduled Execution included, which refuse with a message."""
    import ctypes
    import re

    header = (_headers() / "fmi3Functions.h").read_text()
    names = re.findall(r"^\s*FMI3_Export\s+fmi3\w+TYPE\s+(fmi3\w+);", header, re.MULTILINE)
    assert len(names) > 70
    for model in MODELS:
        with zipfile.ZipFile(fmu_path(model, fmi_version=3)) as archive:
            library = archive.extract(f"binaries/{PLATFORMS[3]['linux']}/{model}.so", tmp_path / model)
        loaded = ctypes.CDLL(library)
        assert [n for n in names if not hasattr(loaded, n)] == [], model


@pytest.mark.parametrize("model", MODELS)
def test_fmi3_runs_in_fmpy_equal_to_fmi2(model):
    runs = [fmpy.simulate_fmu(str(fmu_path(model, fmi_version=v)), stop_time=0.05, step_size=STEP,
                              start_values=inputs_of(model)) for v in VERSIONS]
    names = [v.name for v in _outputs(fmpy.read_model_description(str(fmu_path(model))))]
    moved = 0
    for name in names:
        assert np.array_equal(runs[0][name], _column(runs[1], name, model)), name
        moved += np.ptp(runs[0][name]) > 0
    assert moved >= len(names) // 3  # the inputs drive the model: its outputs change


def test_fmi3_refuses_what_it_must_name():
    """An FMI 3.0 instance refuses, with a message, what its description rules out."""
    from fmpy import extract
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi3 import FMU3Slave

    path = fmu_path("Quadrotor", fmi_version=3)
    description = fmpy.read_model_description(str(path))
    vr = {v.name: v.valueReference for v in description.modelVariables}
    messages = []

    def slave():
        return FMU3Slave(guid=description.guid, unzipDirectory=extract(str(path)), modelIdentifier="Quadrotor",
                         instanceName="q")

    def log(env, status, category, message):
        messages.append(message.decode())

    with pytest.raises(Exception, match="Failed to instantiate"):
        slave().instantiate(eventModeUsed=True, logMessage=log)
    assert any("has no event mode" in m for m in messages)
    fmu = slave()
    fmu.instantiate(logMessage=log)
    try:
        fmu.enterInitializationMode()
        with pytest.raises(FMICallException):
            fmu.getFloat64([9999])
        assert "unknown value reference 9999" in messages[-1]
        with pytest.raises(FMICallException):
            fmu.getFloat64([vr["m"]], nValues=2)
        assert "2 values for value references that hold 1" in messages[-1]
        with pytest.raises(FMICallException):
            fmu.getInt32([vr["m"]])  # a Float64's reference is no Int32's
        assert f"unknown value reference {vr['m']}" in messages[-1]
        mass = next(v.start for v in table("Quadrotor").variables if v.name == "m")
        assert fmu.getFloat64([0, vr["m"]]) == [0.0, mass]  # time and a parameter in one call
        fmu.setBoolean([vr["clamped"]], [True])
        assert fmu.getBoolean([vr["clamped"]]) == [True]
        fmu.exitInitializationMode()
        with pytest.raises(FMICallException):
            fmu.setFloat64([vr["m"]], [2.0])
        assert "parameter m can only be set before initialization ends" in messages[-1]
        fmu.doStep(0.0, STEP)
        assert fmu.getFloat64([0]) == [STEP]
        fmu.terminate()
    finally:
        fmu.freeInstance()


def test_an_fmi3_array_is_read_whole_by_its_first_reference():
    from fmpy import extract
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi3 import FMU3Slave

    path = fmu_path("IMU", fmi_version=3)
    description = fmpy.read_model_description(str(path))
    acc = next(v.valueReference for v in description.modelVariables if v.name == "acc")
    messages = []
    fmu = FMU3Slave(guid=description.guid, unzipDirectory=extract(str(path)), modelIdentifier="IMU", instanceName="i")
    fmu.instantiate(logMessage=lambda env, status, category, message: messages.append(message.decode()))
    try:
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        fmu.doStep(0.0, STEP)
        x, y, z = fmu.getFloat64([acc], nValues=3)
        assert z == pytest.approx(-9.81, abs=0.5) and abs(x) < 0.5 and abs(y) < 0.5  # level, at rest: gravity
        with pytest.raises(FMICallException):
            fmu.getFloat64([acc + 1])  # acc_y has no reference of its own
        assert f"unknown value reference {acc + 1}" in messages[-1]
        with pytest.raises(FMICallException):
            fmu.getFloat64([acc])
        assert "1 values for value references that hold 3" in messages[-1]
        fmu.terminate()
    finally:
        fmu.freeInstance()


# ---------------------------------------------------------------- the Windows binaries under Wine


def _wine() -> str | None:
    return shutil.which("wine") or shutil.which("wine64") or next(
        (p for p in ("/usr/lib/wine/wine64",) if os.access(p, os.X_OK)), None)


def _headers() -> Path:
    return Path(fmpy.__file__).parent / "c-code"


def _plan(folder: Path, platform: str, windows_paths: bool) -> tuple[Path, dict]:
    """The driver's plan for the eight FMUs' binaries of one platform, and their output files."""
    def native(path: Path) -> str:
        return "Z:" + str(path).replace("/", "\\") if windows_paths else str(path)

    lines, outputs = [], {}
    for version in VERSIONS:
        for model in MODELS:
            path = fmu_path(model, fmi_version=version)
            unzipped = folder / f"fmi{version}-{model}"
            with zipfile.ZipFile(path) as archive:
                archive.extractall(unzipped)
            description = fmpy.read_model_description(str(path))
            by_name = {v.name: v.valueReference for v in description.modelVariables}
            suffix = ".dll" if platform == "windows" else ".so"
            library = unzipped / "binaries" / PLATFORMS[version][platform] / f"{model}{suffix}"
            output = folder / f"{platform}-fmi{version}-{model}.bin"
            inputs = " ".join(f"{by_name[n]} {value!r}" for n, value in inputs_of(model).items())
            variables = _outputs(description)
            refs = " ".join(str(v.valueReference) for v in variables)
            lines += [f"{version} {native(library)} {model} {description.guid} {STEPS} {STEP!r}",
                      f"{len(inputs_of(model))} {inputs}", f"{len(variables)} {_values(variables)} {refs}",
                      native(output)]
            outputs[version, model] = (output, _values(variables))
    plan = folder / f"{platform}.plan"
    plan.write_text("\n".join(lines) + "\n")
    return plan, outputs


def _read(output: Path, columns: int) -> np.ndarray:
    values = np.fromfile(output, dtype="<f8")
    assert values.size == (STEPS + 1) * columns, output
    return values.reshape(STEPS + 1, columns)


@pytest.fixture(scope="module")
def linux_outputs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("linux")
    driver = folder / "fmu_driver"
    subprocess.run(["cc", "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-I", str(_headers()),
                    str(HERE / "fmu_driver.c"), "-ldl", "-o", str(driver)], check=True)
    plan, outputs = _plan(folder, "linux", windows_paths=False)
    done = subprocess.run([str(driver), str(plan)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return {key: _read(path, n) for key, (path, n) in outputs.items()}


def test_the_linux_binaries_of_both_versions_agree(linux_outputs):
    for model in MODELS:
        fmi2, fmi3 = linux_outputs[2, model], linux_outputs[3, model]
        assert np.isfinite(fmi2).all() and np.array_equal(fmi2, fmi3), model
        assert (np.ptp(fmi2, axis=0) > 0).sum() >= fmi2.shape[1] // 3, model  # the inputs drive it


def test_the_windows_binaries_under_wine_equal_the_linux_ones(linux_outputs, tmp_path):
    mingw, wine = windows_compiler(), _wine()
    if not (mingw and wine):
        pytest.skip("needs mingw-w64 and Wine (Debian: gcc-mingw-w64-x86-64 wine64; `make windows-tools`)")
    driver = tmp_path / "fmu_driver.exe"
    subprocess.run([mingw, "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-I", str(_headers()),
                    str(HERE / "fmu_driver.c"), "-o", str(driver)], check=True)
    plan, outputs = _plan(tmp_path, "windows", windows_paths=True)
    # one Wine start for all eight (its start-up, not the FMUs, is what takes the time)
    env = os.environ | {"WINEPREFIX": str(tmp_path / "wine"), "WINEDEBUG": "-all",
                        "WINEDLLOVERRIDES": "mscoree,mshtml="}
    try:
        done = subprocess.run([wine, str(driver), "Z:" + str(plan).replace("/", "\\")], capture_output=True,
                              text=True, env=env, timeout=300)
    finally:
        server = shutil.which("wineserver") or "/usr/lib/wine/wineserver"
        subprocess.run([server, "-k"], env=env, capture_output=True)
    assert done.returncode == 0, done.stderr
    for key, (path, n) in outputs.items():
        assert np.array_equal(_read(path, n), linux_outputs[key]), key


def test_without_mingw_the_build_ships_linux_alone_and_says_so_once(tmp_path, monkeypatch, capsys):
    from quadcosim.fmus import build

    monkeypatch.setenv("CC_WIN64", "no-such-mingw-gcc")
    build.windows_compiler.cache_clear()
    try:
        paths = [build.build_fmu("InfraredSensor", tmp_path, fmi_version=v) for v in VERSIONS]
    finally:
        build.windows_compiler.cache_clear()
    for version, path in zip(VERSIONS, paths, strict=True):
        with zipfile.ZipFile(path) as archive:
            platforms = {Path(n).parts[1] for n in archive.namelist() if n.startswith("binaries/")}
        assert platforms == {PLATFORMS[version]["linux"]}
    assert capsys.readouterr().err.count("no no-such-mingw-gcc (mingw-w64") == 1


def test_an_up_to_date_fmu_is_not_rebuilt(tmp_path):
    from quadcosim.fmus.build import build_all

    first = build_all(tmp_path, models=("InfraredSensor",), fmi_versions=(3,), verbose=False)
    stamp = first[0].stat().st_mtime_ns
    assert build_all(tmp_path, models=("InfraredSensor",), fmi_versions=(3,), verbose=False) == first
    assert first[0].stat().st_mtime_ns == stamp
    build_all(tmp_path, models=("InfraredSensor",), fmi_versions=(3,), verbose=False, force=True)
    assert first[0].stat().st_mtime_ns > stamp


@pytest.mark.parametrize("model", MODELS)
def test_fmi3_survives_random_calls(model):
    """Random FMI 3.0 calls, freed instances and null arrays included: every call returns OK,
    Warning or Error (no crash), a refusal leaves a message, and an OK step gives finite outputs."""
    import ctypes

    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave, fmi3ValueReference

    path = fmu_path(model, fmi_version=3)
    description = fmpy.read_model_description(str(path))
    outputs = [v.valueReference for v in _outputs(description)]
    n_values = _values(_outputs(description))
    top = max(v.valueReference for v in description.modelVariables)
    fmu = FMU3Slave(guid=description.guid, unzipDirectory=extract(str(path)), modelIdentifier=model,
                    instanceName="fuzz")
    messages = []
    fmu.instantiate(logMessage=lambda env, status, category, message: messages.append(message))
    f, rng, statuses = fmu.dll, np.random.default_rng(46), []
    instance, t = fmu.component, 0.0

    def refs(n):
        drawn = rng.integers(0, top + 3, n) if rng.random() < 0.9 else rng.integers(0, 2**32, n)
        return (fmi3ValueReference * n)(*drawn.tolist())

    for call in range(3000):
        kind, n = rng.integers(0, 9), int(rng.integers(0, 4))
        count = n if rng.random() < 0.9 else n + 1
        floats = (ctypes.c_double * (n + 1))(*rng.choice([0.5, -1e300, np.nan, np.inf, 3.0], n + 1))
        before = len(messages)
        if kind == 0:
            status = f.fmi3GetFloat64(instance, refs(n), n, floats if rng.random() < 0.95 else None, count)
        elif kind == 1:
            status = f.fmi3SetFloat64(instance, refs(n), n, floats, count)
        elif kind == 2:
            status = f.fmi3GetInt32(instance, refs(n), n, (ctypes.c_int32 * (n + 1))(), count)
        elif kind == 3:
            status = f.fmi3SetBoolean(instance, refs(n), n, (ctypes.c_bool * (n + 1))(True), count)
        elif kind == 4:
            status = f.fmi3EnterInitializationMode(instance, False, 0.0, t, False, 0.0)
        elif kind == 5:
            status = f.fmi3ExitInitializationMode(instance)
        elif kind == 6:
            h = float(rng.choice([1e-3, 0.05, -1e-3, np.nan]))
            flags, last = [ctypes.c_bool() for _ in range(3)], ctypes.c_double()
            status = f.fmi3DoStep(instance, t, h, True, *map(ctypes.byref, flags), ctypes.byref(last))
            if status == 0:
                t += h
                values = (ctypes.c_double * n_values)()
                assert f.fmi3GetFloat64(instance, (fmi3ValueReference * len(outputs))(*outputs), len(outputs),
                                        values, n_values) == 0
                assert np.isfinite(list(values)).all(), (model, call)
        elif kind == 7:
            status, t = f.fmi3Reset(instance), 0.0
        else:  # a fresh instance, the old one freed: calls on it must be refused, not crash
            f.fmi3FreeInstance(instance)  # (fmpy's freeInstance would unload the library too)
            status = f.fmi3Reset(instance)
            assert status == 3, (model, call)
            fmu.instantiate(logMessage=lambda env, status, category, message: messages.append(message))
            instance, t = fmu.component, 0.0
            continue
        assert status in (0, 1, 3), (model, call, kind, status)
        statuses.append(status)
        if status == 3 and kind != 8:
            assert len(messages) > before, (model, call, kind)
    fmu.freeInstance()
    assert statuses.count(0) > 300 and statuses.count(3) > 300  # both paths were taken
