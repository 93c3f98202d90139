"""The MATLAB loader and plotting script read a run's ``results.mat``: checked with Octave when it
is installed, and always against ``scipy.io`` (the fields the scripts read are the fields the
file holds)."""

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from scipy.io import loadmat

from quadcosim import orchestrator, scenarios

SCRIPTS = Path(orchestrator.__file__).resolve().parent / "matlab"


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("matlab") / "tp"
    result, _ = scenarios.run("tp", {"duration": 1.0}, out, formats=("npz", "mat"))
    return out, result


def test_the_file_holds_what_the_scripts_read(run):
    out, result = run
    mat = loadmat(out / "results.mat", struct_as_record=False, squeeze_me=False)
    assert mat["time"].shape == (len(result.time), 1)
    imu, units = mat["IMU"][0, 0], mat["units"][0, 0]
    assert np.array_equal(imu.acc_z[:, 0], result["IMU.acc_z"])
    assert imu.acc.shape == (len(result.time), 3) and np.array_equal(imu.acc, result["IMU.acc"])
    assert units.IMU[0, 0].acc_z[0] == "m/s2" and units.IMU[0, 0].acc[0] == "m/s2"
    load, plot = (SCRIPTS / "quadcosim_load.m").read_text(), (SCRIPTS / "quadcosim_plot.m").read_text()
    assert "fullfile(run, 'results.mat')" in load and "isfield(r, 'units')" in load
    assert "r.(parts{1}).(parts{2})" in plot and "r.units.(parts{1}).(parts{2})" in plot


@pytest.mark.skipif(shutil.which("octave-cli") is None, reason="Octave is not installed (apt-get install octave)")
def test_octave_loads_a_run_and_the_plot_script_checks_its_names(run, tmp_path):
    """Octave reads the file through quadcosim_load (values to the last bit, units); the plotting
    script is run up to its name check (this machine's Octave cannot render text without a
    display)."""
    out, result = run

    def octave(script):
        return subprocess.run(["octave-cli", "--no-gui", "--quiet", "--eval", f"addpath('{SCRIPTS}'); {script}"],
                              capture_output=True, text=True, timeout=120)

    done = octave(f"r = quadcosim_load('{out}'); printf('%d %d %.17g %s\\n', numel(r.time), size(r.IMU.acc, 2), "
                  "r.IMU.acc_z(end), r.units.IMU.acc_z);")
    assert done.returncode == 0, done.stderr
    samples, columns, last, unit = done.stdout.split()[-4:]
    assert int(samples) == len(result.time) and int(columns) == 3 and unit == "m/s2"
    assert float(last) == result["IMU.acc_z"][-1]
    missing = octave(f"quadcosim_load('{tmp_path}')")
    assert missing.returncode != 0 and "no results.mat" in missing.stderr
    wrong = octave(f"quadcosim_plot(quadcosim_load('{out}'), 'IMU.acc', 'IMU.gyr')")
    assert wrong.returncode != 0 and "no recorded signal IMU.gyr" in wrong.stderr
