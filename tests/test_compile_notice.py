"""A numba compilation left for run time says so, once, in one line; `quadcosim build` leaves none
for a run of the lab's scenario."""

import subprocess
import sys

from quadcosim.scenarios import compiled


def test_a_compilation_prints_one_line_once(capsys):
    from numba import njit

    compiled.announce_compiles()
    compiled.announce_compiles()  # installed once

    @njit(cache=False)
    def first(x):
        return x + 1.0

    @njit(cache=False)
    def second(x):
        return x * 2.0

    previous, compiled._announced = compiled._announced, False
    try:
        assert first(1.0) == 2.0 and second(1.0) == 2.0
    finally:
        compiled._announced = previous or compiled._announced
    lines = [line for line in capsys.readouterr().err.splitlines() if "compiling numba code" in line]
    assert len(lines) == 1 and "first" in lines[0] and "quadcosim build" in lines[0]


def test_after_the_build_a_run_loads_every_step_from_the_cache(tmp_path):
    # `make test` runs `quadcosim build` first, which compiles every step (compiled.compile_all)
    done = subprocess.run([sys.executable, "-m", "quadcosim.main", "run", "tp", "--set", "duration=0.2",
                           "estimator=explicit", "--out", str(tmp_path / "tp")], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "compiling numba code" not in done.stderr
