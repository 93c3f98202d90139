"""Silent wrong results and tracebacks of scenario options: ir-calibration's faults scheduled
after the run's end, its GPS fused for less than one sample (the report once failed on NaN axis
limits), and static-cal turn rates that alias to no motion or are NaN."""

import json

import pytest

from quadcosim.main import main as cli


def test_ir_calibration_refuses_a_fault_after_the_runs_end(tmp_path, capsys):
    assert cli(["run", "ir-calibration", "--set", "duration=60", "faults=gps", "--out", str(tmp_path / "r")]) == 2
    assert ("faults=gps: the GPS fault starts at 280 s (the slides' onset), after this run's 60 s; run at least "
            "duration=380") in capsys.readouterr().err
    assert not (tmp_path / "r" / "results.npz").exists()


def test_ir_calibration_with_gps_fused_for_no_sample_draws_its_report(tmp_path):
    out = tmp_path / "r"
    assert cli(["run", "ir-calibration", "--set", "duration=10", "gps_resetting=false", "calibration_s=0.001",
                "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "completed" and "innovations.png" in metrics["files"]


@pytest.mark.parametrize("rates", ["1e6,0,0", "0.2,0.2,50", "nan,1,1", "0,0,0"])
def test_static_cal_refuses_rates_that_alias_or_are_not_numbers(tmp_path, capsys, rates):
    assert cli(["run", "static-cal", "--set", f"rates={rates}", "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert f"option rates = '{rates}': each turn rate must be a finite number of rev/s below 50 (half the 100 Hz" in err
    assert "SVD did not converge" not in err and "Traceback" not in err
