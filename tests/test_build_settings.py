"""Tracebacks on ordinary settings of the build: ``CC="gcc -m64"`` was taken as one program
name (FileNotFoundError), a ``$QUADCOSIM_BUILD_DIR`` or ``$QUADCOSIM_RUNNER_DIR`` that cannot be
written failed with a bare FileNotFoundError naming neither, ``build --out`` on a read-only
folder traced back; and ``quadcosim build`` rebuilt unchanged FMUs each time, saying it was
compiling numba's steps when it only loaded them."""

import os
import subprocess
import sys

import pytest
from quadcosim.fmus import MODELS, BuildFolderRefused, compiler_command
from quadcosim.orchestrator.calls import build_runner

from quadcosim.main import main


def test_cc_with_flags_is_split_as_a_shell_splits_it(tmp_path, monkeypatch):
    monkeypatch.setenv("CC", "gcc -m64")
    assert compiler_command() == ["gcc", "-m64"]
    library = build_runner(tmp_path)
    assert library.is_file() and library.stat().st_size > 1000


def test_a_runner_folder_that_cannot_be_made_names_its_setting(monkeypatch):
    monkeypatch.setenv("QUADCOSIM_RUNNER_DIR", "/proc/runner")
    with pytest.raises(BuildFolderRefused, match=r"/proc/runner/: cannot write the compiled runner there \(.*\); it "
                                                 r"comes from \$QUADCOSIM_RUNNER_DIR=/proc/runner: set "
                                                 r"\$QUADCOSIM_RUNNER_DIR to a writable folder, or unset it"):
        from quadcosim.orchestrator.calls import runner_dir

        build_runner(runner_dir())


def test_a_build_folder_that_cannot_be_made_is_named_in_a_run(tmp_path):
    done = subprocess.run([sys.executable, "-m", "quadcosim.main", "run", "tp", "--set", "duration=0.1", "--out",
                           str(tmp_path / "run")], capture_output=True, text=True, timeout=300,
                          env=os.environ | {"QUADCOSIM_BUILD_DIR": "/proc/build"})
    assert done.returncode != 0
    assert "it comes from $QUADCOSIM_BUILD_DIR=/proc/build" in done.stderr, done.stderr[-2000:]
    assert "Traceback" not in done.stderr


def test_build_out_on_a_read_only_folder_is_refused(tmp_path, capsys):
    folder = tmp_path / "ro"
    folder.mkdir()
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=64k", "tmpfs", str(folder)],
                                           capture_output=True).returncode:
        pytest.skip("mounting a read-only tmpfs is not permitted here")
    try:
        assert main(["build", "--out", str(folder)]) == 1
    finally:
        subprocess.run(["umount", str(folder)], check=True)
    assert f"{folder}/: cannot write the FMUs there (not writable)" in capsys.readouterr().err


def test_build_leaves_unchanged_fmus_and_says_it_loads_numbas_steps(tmp_path, capsys):
    assert main(["build", "--out", str(tmp_path)]) == 0
    built = {m: (tmp_path / f"{m}.fmu").stat().st_mtime_ns for m in MODELS}
    capsys.readouterr()
    assert main(["build", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert all(f"up to date {tmp_path / f'{m}.fmu'}" in out for m in MODELS)
    assert {m: (tmp_path / f"{m}.fmu").stat().st_mtime_ns for m in MODELS} == built
    assert "loaded the numba steps in" in out and "compiling the numba steps" not in out
