"""The FMUs validate, run in plain fmpy, ship their sources, and refuse bad input cleanly."""

import subprocess
import zipfile

import fmpy
import numpy as np
import pytest
from fmpy.validation import validate_fmu
from quadcosim.fmus import MODELS, fmu_path
from quadcosim.fmus.models import sensors
from quadcosim.orchestrator.fmu import FMUError, FMUInstance


@pytest.mark.parametrize("model", MODELS)
def test_validates_and_simulates(model):
    assert validate_fmu(str(fmu_path(model))) == []
    result = fmpy.simulate_fmu(str(fmu_path(model)), stop_time=0.05, step_size=1e-3)
    assert len(result) == 51
    assert all(np.isfinite(result[name]).all() for name in result.dtype.names)


@pytest.mark.parametrize(("version", "api", "platform"), [(2, "shell.c", "linux64"), (3, "fmi3.c", "x86_64-linux")])
@pytest.mark.parametrize("model", MODELS)
def test_source_fmu_rebuilds_from_its_own_sources(model, version, api, platform, tmp_path):
    with zipfile.ZipFile(fmu_path(model, fmi_version=version)) as archive:
        names = archive.namelist()
        assert f"binaries/{platform}/{model}.so" in names
        archive.extractall(tmp_path)
    sources = tmp_path / "sources"
    command = ["cc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-shared", "-fPIC", "-I", str(sources),
               str(sources / api), str(sources / "model.c"), "-lm", "-o", str(tmp_path / "x.so")]
    assert subprocess.run(command, capture_output=True).returncode == 0


@pytest.mark.parametrize("model", MODELS)
def test_nan_input_is_an_error_with_a_message(model):
    fmu = FMUInstance(model)
    name = fmu.inputs[0]
    with pytest.raises(FMUError) as error:
        fmu.set([name], [float("nan")])
    assert name in str(error.value) and "not a finite number" in str(error.value)
    fmu.close()


@pytest.mark.parametrize("model, parameter, value, words",
                         [(name, *refused) for name, member in sensors().items()
                          for refused in member.check("REFUSED_PARAMETERS")])
def test_invalid_parameter_is_an_error_with_a_message(model, parameter, value, words):
    with pytest.raises(FMUError) as error:
        FMUInstance(model, {parameter: value})
    assert words in str(error.value)
    assert "fmi2ExitInitializationMode" in str(error.value)
