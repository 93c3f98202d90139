"""Item 4: two processes never write one output folder. The second is refused with exit 2, naming
the first (pid, command); a lock left by a process that died is taken over."""

import json
import os
import subprocess
import sys
import textwrap

import pytest
from conftest import ROOT, SHORT_TP, assert_whole

from quadcosim.infra.files import LOCK_NAME, FolderBusy, folder_lock, free_folder, held_by
from quadcosim.main import main as cli

HOLDER = textwrap.dedent("""
    import sys, time
    from quadcosim.infra.files import folder_lock
    with folder_lock(sys.argv[1], command="quadcosim run tp --out " + sys.argv[1]):
        print("held", flush=True)
        time.sleep(60)
""")


@pytest.fixture
def held_folder(tmp_path):
    """A folder held by another live process (a run writing there); yields (folder, its pid)."""
    folder = tmp_path / "run"
    folder.mkdir()
    holder = subprocess.Popen([sys.executable, "-c", HOLDER, str(folder)], cwd=ROOT, stdout=subprocess.PIPE,
                              text=True, env=os.environ | {"PYTHONPATH": str(ROOT)})
    try:
        assert holder.stdout.readline().strip() == "held"
        yield folder, holder.pid
    finally:
        holder.kill()
        holder.wait()


def test_a_second_run_into_a_held_folder_is_refused_naming_the_holder(held_folder, capsys):
    folder, pid = held_folder
    assert cli([*SHORT_TP, "--out", str(folder)]) == 2
    err = capsys.readouterr().err
    assert f"is being written by another process: pid {pid}, `quadcosim run tp --out {folder}`" in err
    assert sorted(p.name for p in folder.iterdir()) == [LOCK_NAME]  # nothing of this run, the holder's lock kept
    with pytest.raises(FolderBusy, match=f"pid {pid}"):
        with folder_lock(folder):
            pass
    assert held_by(folder)["pid"] == pid
    assert free_folder(folder) == folder.with_name("run-2")  # a default folder skips a held one


def test_a_second_calibrate_into_a_held_folder_is_refused(held_folder, capsys):
    folder, pid = held_folder
    log = folder.parent / "flight.log"
    log.write_text("FMT, 128, 89, FMT, BBnNZ, Type,Length,Name,Format,Columns\n")
    assert cli(["calibrate", str(log), "--out", str(folder)]) == 2
    assert f"pid {pid}" in capsys.readouterr().err  # refused before the log is even read


def test_a_lock_left_by_a_dead_process_is_taken_over(tmp_path, capsys):
    folder = tmp_path / "run"
    folder.mkdir()
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    (folder / LOCK_NAME).write_text(json.dumps({"pid": int(dead.stdout), "command": "quadcosim run tp"}) + "\n")
    assert held_by(folder) is None
    assert cli([*SHORT_TP, "--out", str(folder)]) == 0
    capsys.readouterr()
    assert assert_whole(folder)["status"] == "completed"  # and the lock removed with the run's end
