"""Sweeps on a real Dask cluster: failures recorded, resume after a kill, identical tables
whatever the workers or the scheduler, FMUs extracted once per worker.

The reference sweep: the lab's closed loop for 0.5 s, noise on, linear filter gains
{0.05, 0.2, 1e5} x seeds {1..4}. The gain 1e5 would make the discrete filter diverge (k dt far
over 2): those members are refused by name and fail, the others must complete.
"""

import json
import math
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from quadcosim.fmus import MODELS
from quadcosim.studies import sweep
from quadcosim.studies.sweep import command, table
from quadcosim.studies.sweep.engine import worker_state

ROOT = Path(__file__).resolve().parent.parent
GRID = ["--grid", "k=0.05,0.2,1e5", "--set", "duration=0.5", "--set", "noise=on", "--seeds", "4"]
MEMBERS, FAILING = 12, 4
BIN = Path(sys.executable).parent


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep") / "two-workers"
    code = command.main(["tp", *GRID, "--workers", "2", "--out", str(out), "--quiet"])
    return code, out, table.read(out)


@pytest.mark.slow
def test_failing_members_are_recorded_and_the_others_complete(reference, capsys):
    code, out, columns = reference
    assert code == 1  # some members failed
    assert len(columns["member"]) == MEMBERS
    failed = [i for i, s in enumerate(columns["status"]) if s != "ok"]
    assert [columns["k"][i] for i in failed] == [1e5] * FAILING
    for i in failed:
        # the diverging gain is refused by name before the filter runs, not found later as a NaN
        assert "gain k1 = 100000 makes the linear filter diverge" in columns["error"][i]
        assert (out / "members" / f"{i:06d}" / "error.txt").read_text().startswith("Traceback")
    finished = [i for i in range(MEMBERS) if i not in failed]
    roll = np.array([columns["rms_error_deg[0]"][i] for i in finished])
    # Lab gain 0.05 with noise on: roll error of a few thousandths of a degree, never NaN.
    assert np.all(np.isfinite(roll)) and np.all(roll < 0.05) and np.all(roll > 1e-4)
    # Different seeds give different noise, hence different errors.
    assert len(set(roll[:4])) == 4
    assert set(columns["worker"][i] for i in range(MEMBERS)) == {"0", "1"}
    # The same table, as Parquet and as CSV.
    assert table.same(columns, table.read(out / "sweep.csv"))
    summary = sweep.Summary(out, MEMBERS, MEMBERS - FAILING, FAILING, MEMBERS, 0, 1.0, 2)
    assert summary.exit_code() == 1 and "4 failed" in summary.text()


@pytest.mark.slow
def test_one_and_two_workers_give_the_same_table(reference, tmp_path):
    _, _, two = reference
    out = tmp_path / "one-worker"
    assert command.main(["tp", *GRID, "--workers", "1", "--out", str(out), "--quiet"]) == 1
    one = table.read(out)
    assert set(one["worker"]) == {"0"}
    assert table.same(one, two)
    assert not table.same(one, {**two, "rms_error_deg[0]": two["rms_error_deg[0]"][::-1]})


@pytest.mark.slow
def test_killed_sweep_resumes_to_the_same_table(reference, tmp_path):
    _, _, uninterrupted = reference
    out = tmp_path / "killed"
    process = subprocess.Popen([sys.executable, "-m", "quadcosim.studies.sweep", "tp", *GRID, "--workers", "1",
                                "--out", str(out), "--quiet"], cwd=tmp_path, start_new_session=True,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    while len(list(out.glob("members/*/metrics.json"))) < 4:
        assert process.poll() is None and time.monotonic() < deadline, "the sweep ended before it was killed"
        time.sleep(0.01)
    os.killpg(process.pid, signal.SIGKILL)
    process.wait()
    done = {p.parent.name: p.stat().st_mtime_ns for p in out.glob("members/*/metrics.json")}
    assert 4 <= len(done) < MEMBERS
    # What was written is whole: every member file parses, and the table (if written yet) too.
    for path in out.glob("members/*/metrics.json"):
        json.loads(path.read_text())
    if (out / "sweep.parquet").exists():
        assert len(table.read(out)["member"]) <= len(done)
    # Without --resume the folder is refused, not overwritten.
    assert command.main(["tp", *GRID, "--out", str(out), "--quiet"]) == 2
    code = command.main(["tp", "--out", str(out), "--resume", "--workers", "2", "--quiet"])
    assert code == 1
    resumed = table.read(out)
    assert table.same(resumed, uninterrupted)
    # Only the missing members ran: the finished ones were not touched.
    assert {p.parent.name: p.stat().st_mtime_ns for p in out.glob("members/*/metrics.json")
            if p.parent.name in done} == done


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.slow
def test_sweep_through_a_separately_started_scheduler(reference, tmp_path):
    from distributed import Client

    _, _, local = reference
    address = f"tcp://127.0.0.1:{_free_port()}"
    scheduler = subprocess.Popen([BIN / "dask", "scheduler", "--host", "127.0.0.1", "--port", address.rsplit(":")[-1],
                                  "--no-dashboard"], cwd=tmp_path, stderr=subprocess.DEVNULL)
    worker = subprocess.Popen([BIN / "dask", "worker", address, "--nthreads", "1", "--no-dashboard"],
                              cwd=tmp_path, stderr=subprocess.DEVNULL)
    try:
        out = tmp_path / "remote"
        assert command.main(["tp", *GRID, "--scheduler", address, "--out", str(out), "--quiet"]) == 1
        assert table.same(table.read(out), local)
        with Client(address) as client:
            state = next(iter(client.run(worker_state).values()))
        # One worker ran every member, from one extraction of each FMU.
        assert state["members"] == MEMBERS
        assert state["extractions"] == len(MODELS)
        assert state["preload_s"] > 0
    finally:
        for process in (worker, scheduler):
            process.terminate()
            process.wait(timeout=30)


@pytest.mark.slow
def test_a_dead_worker_is_retried_then_recorded(tmp_path):
    plan = sweep.plan("tp", ["k=0.05,1500"], ["duration=0.2"])
    summary = sweep.run(plan, tmp_path / "dead", workers=1, retries=1, progress=False,
                        extra_metrics="helpers:exit_worker_on_large_gain")
    columns = table.read(tmp_path / "dead")
    assert columns["status"] == ["ok", "failed"]
    assert columns["attempts"] == [1, 2]
    assert columns["error"][1].startswith("worker lost: KilledWorker")
    assert summary.failed == 1 and summary.exit_code() == 1


@pytest.mark.slow
def test_a_diverged_member_is_an_outcome_never_a_result(tmp_path, capsys):
    # kp = 5000 1/s^2 (the default is 144) crashes the lab's quadrotor: 10 m below its setpoint by t = 4 s
    out = tmp_path / "kp"
    code = command.main(["tp", "--grid", "Controller.kp=144,5000", "--set", "duration=4", "--workers", "1",
                         "--out", str(out), "--quiet"])
    printed = capsys.readouterr()
    assert code == 3  # every member ran, one diverged (documented: the sweeps guide)
    assert printed.out.startswith("2 members: 1 ok, 1 diverged, 0 failed")
    assert "diverged: member 1 (Controller.kp=5000): tp diverged at t = " in printed.out
    assert "UserWarning" not in printed.err and ".py:" not in printed.err  # one-line warnings, no source line
    columns = table.read(out)
    assert columns["status"] == ["ok", "diverged"]
    assert "10.0 m below its altitude setpoint" in columns["error"][1]
    record = json.loads((out / "members" / "000001" / "metrics.json").read_text())
    assert record["status"] == "diverged" and 2.0 < record["diverged"]["at_s"] < 3.0
    assert "signals_not_saved" not in columns  # a member saves no record: no column repeats its list
    assert table.units(out)["Controller.kp"] == "1/s^2" and table.units(out)["rms_error_deg[0]"] == "deg"
    units, _, _ = command._plot_context(out)
    figure = sweep.plot(columns, "rms_error_deg[0]", "Controller.kp", units=units)
    assert figure.axes[0].get_xlabel() == "Controller.kp (1/s^2)"
    lines = {line.get_label(): line for line in figure.axes[0].get_lines()}
    assert list(lines["diverged (1): a crash, no value"].get_xdata()) == [5000.0]
    assert list(lines["rms_error_deg[0]"].get_xdata()) == [144.0]  # the crash is not on the curve
    # --resume keeps a diverged member (its outcome is known) and runs nothing
    assert command.main(["tp", "--out", str(out), "--resume", "--workers", "1", "--quiet"]) == 3
    assert "2 already done" in capsys.readouterr().out


# ------------------------------------------------------------------ without a cluster
def test_grid_values_and_members():
    with pytest.warns(UserWarning, match=r"--grid k: k acts only when estimator=linear; with estimator=explicit it "
                                         r"varies nothing, so those members run once, at k=0.01 \(6 duplicate members "
                                         r"of 16 dropped\)"):
        plan = sweep.plan("tp", ["k=0.01:10:log4", "estimator=linear,explicit"], ["duration=2", "noise=on"],
                          seeds="2")
    assert len(plan.members) == 4 * 2 + 2  # the explicit filter's members, once per seed: k does not act on it
    assert plan.varied == ["k", "estimator", "seed"]
    linear = [m for m in plan.members if m.options["estimator"] == "linear"]
    assert [m.options["k"] for m in linear[::2]] == [0.01, 0.1, 1.0, 10.0]
    assert [m.label for m in plan.members if m.options["estimator"] == "explicit"] == [
        "estimator=explicit seed=1", "estimator=explicit seed=2"]
    assert [m.index for m in plan.members] == list(range(10))
    first = plan.members[0]
    assert first.options | {} == first.options and first.options["duration"] == 2.0
    assert first.options["noise"] is True and first.label == "k=0.01 estimator=linear seed=1"
    assert [m.options["seed"] for m in plan.members[:4]] == [1, 2, 1, 2]
    assert sweep.plan("tp", ["k=0:1:lin5"]).members[2].options["k"] == 0.5
    assert [m.options["seed"] for m in sweep.plan("tp", seeds="3:5", settings=["noise=on"]).members] == [3, 4, 5]
    with pytest.warns(UserWarning, match="--seeds: seed acts only when noise=true; with noise=off it varies nothing"):
        assert [m.options["seed"] for m in sweep.plan("tp", seeds="3:5").members] == [3]


@pytest.mark.parametrize("grids, settings, seeds, message", [
    (["kk=1,2"], [], None, "unknown option 'kk' for scenario tp. Did you mean k"),
    (["k=1,x"], [], None, "option k='x' is not a valid float"),
    (["k=-1,1"], [], None, "must be at least 0.0"),
    (["estimator=linear,kalman"], [], None, "must be one of linear, explicit, passive"),
    (["k=0:1:log3"], [], None, "a log grid needs positive bounds"),
    (["k=0.5:2"], [], None, "integer range"),
    (["seed=1:2:lin3"], [], None, "option seed='1.5' is not a valid int"),
    (["k=1,2"], ["k=3"], None, "both varied (--grid) and fixed (--set)"),
    (["k=1,1"], [], None, "repeated values"),
    (["k"], [], None, "write NAME=VALUES"),
    ([], ["noise=on"], "4", None),
])
def test_bad_grids_are_refused_before_any_run(grids, settings, seeds, message):
    if message is None:
        assert len(sweep.plan("tp", grids, settings, seeds).members) == 4
        return
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)").replace(".", r"\.")):
        sweep.plan("tp", grids, settings, seeds)


def test_seeds_need_a_seed_option(monkeypatch):
    from quadcosim import scenarios

    tp = scenarios.get("tp")
    unseeded = scenarios.Scenario("unseeded", "", {k: o for k, o in tp.options.items() if k != "seed"}, tp.build,
                                  tp.report)
    monkeypatch.setattr(scenarios, "get", lambda name: unseeded)
    with pytest.raises(ValueError, match="has no seed option"):
        sweep.plan("unseeded", seeds="3")
    assert [m.options["k"] for m in sweep.plan("unseeded", ["k=1:3:lin3"]).members] == [1.0, 2.0, 3.0]


def test_table_flattening_and_round_trip(tmp_path):
    record = {"member": 0, "label": "k=1", "status": "ok", "error": None, "attempts": 1, "wall_s": 0.5,
              "worker": "0", "options": {"k": 1.0, "noise": True, "estimator": "linear"},
              "metrics": {"rms": [0.1, 0.2, math.nan], "nested": {"a": 1}, "long": list(range(20)), "k": 3.0}}
    failed = record | {"member": 1, "status": "failed", "error": "SimulationError: x", "metrics": {}}
    rows = [table.row(failed), table.row(record)]
    assert rows[1]["rms[1]"] == 0.2 and rows[1]["nested.a"] == 1 and rows[1]["metric.k"] == 3.0
    assert json.loads(rows[1]["long"]) == list(range(20))
    table.write(rows, tmp_path)
    parquet, csv = table.read(tmp_path), table.read(tmp_path / "sweep.csv")
    assert parquet["member"] == [0, 1] and parquet["status"] == ["ok", "failed"]
    assert parquet["rms[1]"] == [0.2, None] and math.isnan(parquet["rms[2]"][0])
    assert table.same(parquet, csv)
    assert not list(tmp_path.glob(".*tmp"))


def test_rows_kept_on_disk_write_the_table_of_the_rows_in_member_order(tmp_path):
    """Rows that finish out of order, with other columns and kinds of value, give the table that
    the whole rows in member order give: the same columns in the same order, each of the type
    pyarrow infers for the whole column (text where kinds cannot share one), the same values."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    def record(i, status="ok", **metrics):
        return {"member": i, "label": f"seed={i}", "status": status, "error": None if status == "ok" else "x",
                "attempts": 1, "wall_s": 0.5, "worker": "0", "options": {"seed": i, "k": 0.1}, "metrics": metrics}

    records = [record(3, rms=[0.1, 0.2], late=1), record(0, "failed"), record(5, rms=[0.3, 0.4], mixed="text"),
               record(1, rms=[0.5, math.nan], mixed=2.5, huge=2 ** 70), record(2, rms=[0.6, 0.7], mixed=True)]
    kept = table.Rows(6, tmp_path)
    for r in records:
        kept.add(r["member"], table.row(r))
    kept.add(0, table.row(record(0, rms=[0.8, 0.9])))  # a failed member run again
    kept.write(tmp_path)
    again = [r for r in records if r["member"] != 0] + [record(0, rms=[0.8, 0.9])]
    rows = sorted((table.row(r) for r in again), key=lambda r: r["member"])
    written = pq.read_table(tmp_path / "sweep.parquet")
    assert written.column_names == table.columns_of(rows) == kept.names()
    for name in written.column_names:
        values = [r.get(name) for r in rows]
        try:
            expected = pa.array(values)
        except (pa.ArrowInvalid, pa.ArrowTypeError, TypeError, OverflowError):
            expected = pa.array([None if v is None else v if isinstance(v, str) else json.dumps(v) for v in values])
        assert written.schema.field(name).type == expected.type, name
        assert written.column(name).to_pylist() == expected.to_pylist() or name == "rms[1]", name
    assert (len(kept), kept.ok, kept.failures) == (5, 5, {})
    kept.close()


def test_the_rows_of_a_large_sweep_take_bytes_per_member_in_memory(tmp_path):
    """The table's rows go to disk: memory keeps where each is, 17 bytes a member, and per
    column its kinds (``python -m quadcosim.benchmarks.sweep_memory`` measures a whole sweep's client)."""
    import tracemalloc

    members = 20_000
    row = table.row({"member": 0, "label": "x", "status": "ok", "error": None, "options": {"seed": 1, "k": 0.1},
                     "metrics": {"rms": [0.1, 0.2, 0.3], "steady": 1.5, "figures": None}})
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        kept = table.Rows(members, tmp_path)
        for i in range(members):
            kept.add(i, row | {"member": i, "label": f"seed={i}", "steady": i * 0.5})
        grown = (tracemalloc.get_traced_memory()[0] - before) / members
    finally:
        tracemalloc.stop()
    kept.close()
    assert grown < 25  # bytes per member (measured: 18; 17 of them say where each row is and how it ended)


def test_figure_pools_seeds_and_groups(tmp_path):
    columns = {"member": list(range(8)), "status": ["ok"] * 7 + ["failed"],
               "k": [0.1, 0.1, 1.0, 1.0, 0.1, 0.1, 1.0, 1.0], "estimator": ["linear"] * 4 + ["explicit"] * 4,
               "err": [1.0, 3.0, 2.0, 4.0, 5.0, 7.0, 6.0, None]}
    figure = sweep.plot(columns, "err", "k", by="estimator")
    lines = {line.get_label(): line for line in figure.axes[0].get_lines() if not line.get_label().startswith("_")}
    assert np.allclose(lines["estimator = linear (mean of 2)"].get_ydata(), [2.0, 3.0])
    assert np.allclose(lines["estimator = explicit (mean of up to 2)"].get_ydata(), [6.0, 6.0])
    assert figure.axes[0].get_xscale() == "linear"
    assert "1 failed member not shown" in figure.axes[0].get_title()
    path = sweep.plot(columns, "err", "estimator", out=tmp_path / "by-estimator.png")
    assert Path(path).stat().st_size > 10_000
    with pytest.raises(KeyError, match="no column 'erro'. Did you mean err"):
        sweep.plot(columns, "erro", "k")


def test_figure_orders_curves_and_categories_as_numbers():
    columns = {"status": ["ok"] * 6, "imu_rate": [16, 24, 8, 16, 24, 8], "k": [1, 1, 1, 2, 2, 2],
               "mode": ["10", "2", "a"] * 2, "err": [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]}
    figure = sweep.plot(columns, "err", "k", by="imu_rate", units={"imu_rate": "Hz"})
    labels = [t.get_text() for t in figure.axes[0].get_legend().get_texts()]
    assert labels == ["imu_rate = 8 Hz", "imu_rate = 16 Hz", "imu_rate = 24 Hz"]
    figure = sweep.plot(columns, "err", "mode")
    assert [t.get_text() for t in figure.axes[0].get_xticklabels()] == ["2", "10", "a"]


@pytest.mark.parametrize("settings, message", [
    ({"burn_in": 300.0, "duration": 200.0}, "burn_in = 300 s must be shorter than duration = 200 s"),
    ({"duration": 400.0}, "give duration >= 600 s"),
    ({"k_max": 200.0}, "k dt = 2 must stay below 1"),
    ({"k_min": 2.0, "k_max": 1.0}, "k_max = 1.0 must exceed k_min = 2.0"),
])
def test_gain_study_options_are_checked_before_any_run(settings, message, monkeypatch):
    from quadcosim.orchestrator import System

    from quadcosim import scenarios

    def no_run(*args, **kwargs):
        raise AssertionError("a run started with invalid options")

    monkeypatch.setattr(System, "run", no_run)
    with pytest.raises(ValueError, match=message.replace(".", r"\.")):
        scenarios.run("gain-study", settings)


def test_lab_matrix_is_a_named_sweep_of_every_case():
    from quadcosim.studies import lab_matrix
    from quadcosim.studies.sweep import named

    plan = named.get("lab-matrix").plan(["noise=on"])
    labels = [m.label for m in plan.members]
    assert labels[:len(lab_matrix.CASES) + 10] == list(lab_matrix.CASES) + list(lab_matrix.COMPARISON)
    assert {m.options["estimator"] for m in plan.members if m.label in lab_matrix.COMPARISON} == {
        "linear", "explicit", "passive", "vqf", "madgwick"}
    assert len(labels) == (len(lab_matrix.CASES) + len(lab_matrix.COMPARISON) + len(lab_matrix.EXPLICIT_GAINS)
                           + 2 * len(lab_matrix.PASSIVE_GAINS))
    assert all(m.options["noise"] is True for m in plan.members)
    passive = plan.members[-1].options  # TRIAD, kP = kI = 100: 1.5 times the predicted convergence, at least 10 s
    assert passive["ry"] == "triad" and passive["kP"] == 100.0 and passive["duration"] == 10.0


def test_the_lab_matrix_marks_its_diverged_member():
    """The passive filter on TRIAD, estimate-fed in non-stationary flight, crashes (roll 60 deg off
    its setpoint at t = 15.7 s): summary.md prints its numbers as a crash, and lists it."""
    from quadcosim.studies import lab_matrix
    from quadcosim.studies.sweep.engine import run_member

    from quadcosim import scenarios

    name = "compare-passive-nonstationary"
    record = run_member("tp", scenarios.get("tp").parse(lab_matrix.COMPARISON[name]),
                        extra_metrics="quadcosim.studies.lab_matrix:late_mean_error")
    assert record["status"] == "diverged" and "roll 60 deg from its setpoint" in record["error"]
    metrics = record["metrics"]
    summary = {"diverged": {name: record["error"]}, "cases": {}, "explicit_steady_bias_error_deg": [],
               "passive_bias_convergence_s": [],
               "comparison": {name: {k: metrics[k] for k in ("quaternion_rmse_deg", "rms_error_deg",
                                                             "tracking_rms_deg")} | {"status": "diverged"}}}
    text = lab_matrix.markdown(summary)
    row = next(line for line in text.splitlines() if line.startswith("| nonstationary | passive |"))
    assert row.count("DIVERGED (a crash: ") == 3
    assert f"- {name}: tp diverged at t = " in text
