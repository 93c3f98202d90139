"""Sweeps at their edges: a plan too large is refused by its count before any member is made,
planning gives way to Ctrl-C, a value a member would fail on stops the sweep before its cluster
starts, and --resume names a corrupt member file and runs that member again, or refuses a
folder that holds no sweep."""

import json
import signal
import subprocess
import sys
import time
import tracemalloc

import pytest
from quadcosim.studies.sweep import command, grid, table


def test_a_plan_over_the_limit_is_refused_by_its_count_before_any_value_is_made(capsys, tmp_path):
    grid.plan("tp", ["k=1,2"])  # the scenario imported, so that only the refusal is timed
    started = time.thread_time()  # CPU time: a busy machine's preemptions do not count
    tracemalloc.start()
    with pytest.raises(ValueError, match=r"the plan has 100,000,000 members \(100,000,000 k\), more than the "
                                         r"1,000,000 allowed"):
        grid.plan("tp", ["k=0.1:1:log100000000"])
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert time.thread_time() - started < 1.0 and peak < 64 * 1024  # measured 1.6 kB: no value list is made
    out = tmp_path / "huge"
    assert command.main(["tp", "--grid", "k=0.1:1:log100000000", "--out", str(out), "--quiet"]) == 2
    assert "100,000,000 members" in capsys.readouterr().err and not out.exists()
    assert command.main(["tp", "--grid", "k=0.1:1:log30", "--seeds", "40", "--max-members", "1000",
                         "--out", str(out), "--quiet"]) == 2
    assert "the plan has 1,200 members (30 k x 40 seed)" in capsys.readouterr().err


def test_a_100000_member_plan_is_made_member_by_member_in_little_memory():
    grid.plan("tp", ["k=1,2"])  # the scenario imported, so that only the plan is measured
    tracemalloc.start()
    plan = grid.plan("tp", ["estimator=linear,explicit"], ["duration=5", "noise=on"], seeds="50000")
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert len(plan.members) == 100_000
    last = plan.members[-1]
    assert (last.index, last.options["estimator"], last.options["seed"], last.options["duration"]) == \
        (99_999, "explicit", 50_000, 5.0)
    assert last.label == "estimator=explicit seed=50000"
    assert plan.members[50_000].options["seed"] == 1
    print(f"a 100,000-member plan: peak allocation {peak / 2**20:.2f} MiB")
    assert peak < 8 * 2**20  # measured 5.9 MiB; the 100,000 members' options would take over 100 MB


@pytest.mark.parametrize("cpu_s", [0.4, 3.0], ids=["loading", "planning"])
def test_planning_gives_way_to_ctrl_c(cpu_s, tmp_path):
    import psutil

    process = subprocess.Popen([sys.executable, "-m", "quadcosim.studies.sweep", "tp", "--grid", "k=0.1:1:log990000",
                                "--seeds", "1", "--out", str(tmp_path / "long"), "--quiet"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    # (a child of a background job would otherwise inherit SIGINT ignored, as a shell wants)
    # 0.4 s of CPU: loading numpy and the scenarios (about a second in all); 3 s: making and
    # checking the 990,000 values (several)
    child, deadline = psutil.Process(process.pid), time.monotonic() + 120
    while sum(child.cpu_times()[:2]) < cpu_s:
        assert process.poll() is None and time.monotonic() < deadline, "planning ended before the signal"
        time.sleep(0.01)
    process.send_signal(signal.SIGINT)
    sent = time.perf_counter()
    _, err = process.communicate(timeout=60)
    assert process.returncode == 130 and err.strip().endswith("quadcosim sweep: interrupted"), err[-3000:]
    assert time.perf_counter() - sent < 15.0
    assert not (tmp_path / "long").exists()


@pytest.mark.parametrize("arguments, refused", [
    (["--grid", "IMU.gyro_noise_density=0.001,-1"], "member 1 (IMU.gyro_noise_density=-1) would fail"),
    (["--set", "Quadrotor.m=-1"], "member 0 (the fixed options) would fail"),
    (["--grid", "IMU.gyro_noise_dnsity=0.001,0.002"], "gyro_noise_density"),
])
def test_a_value_a_member_would_fail_on_stops_the_sweep_before_its_cluster(arguments, refused, capsys, tmp_path):
    out = tmp_path / "refused"
    started = time.perf_counter()
    assert command.main(["tp", *arguments, "--set", "duration=0.2", "noise=on", "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert refused in err and "No member was run" in err
    assert not out.exists()  # nothing written, and no cluster started (which alone takes seconds)
    assert time.perf_counter() - started < 5.0


def test_resume_names_a_corrupt_member_file_and_runs_that_member_again(capsys, tmp_path):
    out = tmp_path / "sweep"
    arguments = ["tp", "--grid", "k=0.05,0.1", "--set", "duration=0.2", "noise=on", "--workers", "1",
                 "--out", str(out), "--quiet"]
    assert command.main(arguments) == 0
    before = table.read(out)
    corrupt = out / "members" / "000001" / "metrics.json"
    corrupt.write_text(corrupt.read_text()[:40])  # cut short, as by a full disk
    untouched = (out / "members" / "000000" / "metrics.json").stat().st_mtime_ns
    capsys.readouterr()
    assert command.main(["tp", "--out", str(out), "--resume", "--workers", "1", "--quiet"]) == 0
    err = capsys.readouterr().err
    assert f"{corrupt} is unreadable" in err and "that member runs again" in err
    assert json.loads(corrupt.read_text())["status"] == "ok"
    assert (out / "members" / "000000" / "metrics.json").stat().st_mtime_ns == untouched
    assert table.same(table.read(out), before)


def test_resume_on_a_folder_without_a_plan_is_refused(capsys, tmp_path):
    out = tmp_path / "never-run"
    assert command.main(["tp", "--out", str(out), "--resume", "--quiet"]) == 2
    assert "holds no sweep (no sweep.json)" in capsys.readouterr().err
    assert not out.exists()
    (out / "members").mkdir(parents=True)  # a folder, but no plan in it
    assert command.main(["tp", "--grid", "k=0.05,0.1", "--out", str(out), "--resume", "--quiet"]) == 2
    assert "holds no sweep" in capsys.readouterr().err


SHORT = ["tp", "--grid", "k=0.05,0.1", "--set", "duration=0.2", "noise=on", "--quiet"]


def test_two_sweeps_into_one_folder_at_once_the_second_is_refused(tmp_path):
    import socket

    out = tmp_path / "shared"
    command_line = [sys.executable, "-m", "quadcosim.studies.sweep", *SHORT, "--workers", "1", "--out", str(out)]
    dashboard = socket.socket()  # Dask's default dashboard port taken, as by another cluster
    try:
        dashboard.bind(("", 8787))
        dashboard.listen()
    except OSError:
        pass  # taken already
    try:
        both = [subprocess.Popen(command_line, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                for _ in range(2)]
        ended = [(process.wait(timeout=300), *process.communicate()) for process in both]
    finally:
        dashboard.close()
    noise = [err for _, _, err in ended if "8787" in err or "unclosed" in err]
    assert not noise, noise  # neither Dask's port warning nor an unclosed socket
    codes = sorted(code for code, _, _ in ended)
    assert codes == [0, 2], ended
    refused = next(err for code, _, err in ended if code == 2)
    # refused while the first holds the folder, or (on a slow start) because it holds its finished sweep
    assert "is being written by another process: pid" in refused or "already holds a sweep of tp" in refused
    stored = json.loads((out / "sweep.json").read_text())
    columns = table.read(out)
    assert stored["count"] == 2 and columns["status"] == ["ok", "ok"] and columns["k"] == [0.05, 0.1]
    assert not (out / ".quadcosim.lock").exists()


@pytest.mark.parametrize("scheduler, refused", [
    ("inproc://x", "inproc:// reaches only a scheduler inside this same process"),
    ("tls://127.0.0.1:1", "tls:// needs this client's TLS certificate"),
    ("127.0.0.1:8786", "is not a scheduler's address: give tcp://HOST:PORT"),
    ("tcp://127.0.0.1", "no port in it"),
    ("tcp://127.0.0.1:1", "cannot reach the Dask scheduler at tcp://127.0.0.1:1 within 1 s"),
])
def test_a_scheduler_that_cannot_be_used_is_refused_and_nothing_is_left(scheduler, refused, capsys, tmp_path):
    out = tmp_path / "a" / "sweep"
    started = time.perf_counter()
    assert command.main([*SHORT, "--scheduler", scheduler, "--connect-timeout", "1", "--out", str(out)]) == 2
    assert refused in capsys.readouterr().err
    assert not (tmp_path / "a").exists()  # a refused sweep leaves nothing, not even its folder
    assert time.perf_counter() - started < 30.0  # measured 3 s (1 s of it the connect timeout)


def test_folders_that_cannot_take_a_sweep_are_named(capsys, tmp_path):
    (tmp_path / "loop").symlink_to(tmp_path / "loop")
    (tmp_path / "dangling").symlink_to(tmp_path / "nowhere")
    (tmp_path / "file").write_text("")
    for name, refused in (("loop", "a symbolic link that leads back to itself (a loop)"),
                          ("loop/sub", "(above it) is a symbolic link that leads back to itself"),
                          ("dangling", f"a symbolic link to {tmp_path / 'nowhere'}, which does not exist"),
                          ("file", "a file of that name exists"), ("file/sub", "is a file, so no folder")):
        assert command.main([*SHORT, "--out", str(tmp_path / name)]) == 2
        assert refused in capsys.readouterr().err
    assert not (tmp_path / "nowhere").exists()
    assert command.main([*SHORT, "--max-members", "0", "--out", str(tmp_path / "x")]) == 2
    assert "--max-members 0: give at least 1" in capsys.readouterr().err


def test_resume_refuses_a_folder_whose_members_are_another_plans(capsys, tmp_path):
    out = tmp_path / "sweep"
    assert command.main([*SHORT, "--workers", "1", "--out", str(out)]) == 0
    record = out / "members" / "000001" / "metrics.json"
    mixed = json.loads(record.read_text())
    mixed["options"]["k"] = 7.0  # as a second sweep into the folder would have left it
    record.write_text(json.dumps(mixed))
    assert command.main(["tp", "--out", str(out), "--resume", "--workers", "1", "--quiet"]) == 2
    assert f"{record} was run with other options than the plan's member 1 (differing: k)" in capsys.readouterr().err
