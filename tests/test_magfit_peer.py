"""The peer column: MAVExplorer's magfit run on the training part of a shared log only, and its
parameters scored on the held-out part as quadcosim's export is; or the reason it cannot run."""

import pytest

import scenarios.findings as findings
from scenarios.findings import magfit
from tests import flightlog_data


@pytest.fixture
def logs(monkeypatch):
    monkeypatch.setenv("QUADCOSIM_FLIGHT_LOGS", str(flightlog_data.FOLDER))
    flightlog_data.path(flightlog_data.QUAD[1])


def _peer(key, compass, settings):
    try:
        return magfit.peer(key, compass, settings)
    except findings.Skipped as reason:
        pytest.skip(str(reason))


def test_without_mavproxy_the_group_is_skipped_naming_the_install(monkeypatch):
    from importlib import metadata

    def absent(name):
        raise metadata.PackageNotFoundError(name)

    monkeypatch.setattr(metadata, "version", absent)
    with pytest.raises(findings.Skipped, match=r'pip install "quadcosim\[peers\]"'):
        magfit.compute(quick=True)


def test_magfit_cannot_run_without_a_gps_fix_and_says_so(logs):
    result = _peer("erlebrain", 0, ("offsets",))
    assert result == {"cannot_run": "no GPS fix in the training part: magfit's target is the World Magnetic "
                                    "Model's field at a 3D fix, and the log has none"}


@pytest.mark.slow
def test_magfit_fits_the_training_part_only_and_is_scored_on_the_held_out_part(logs):
    result = _peer("b", 1, ("offsets",))
    fit = result["offsets"]
    # it saw the training samples (the first, before any attitude, is dropped by magfit), none held out
    assert fit["samples"] - 1 <= fit["points"] <= fit["samples"]  # 324 of 325 measured
    # its offsets (mGauss) correct the internal compass: 3.79 deg RMS held out, 11.43 as flown
    assert set(fit["params"]) >= {"COMPASS_OFS2_X", "COMPASS_OFS2_Y", "COMPASS_OFS2_Z"}
    assert 3.0 < fit["heading_rms_deg"] < 4.5 and 11.0 < result["as_flown"]["heading_rms_deg"] < 12.0
