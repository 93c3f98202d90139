"""Item 8: the memory check counts the writers' peak and the process's limits (ulimit -v,
cgroup v1 and v2), and refuses a run before it starts with the figure and the way out."""

import os
import resource
import subprocess
import sys
import tracemalloc
from collections import Counter

import numpy as np
import pytest
from conftest import ROOT
from quadcosim.orchestrator import Result
from quadcosim.orchestrator.signals import vector_groups

from quadcosim.infra.memory import cgroup_left, writers_peak

GIB = 2 ** 30


def _group(folder, **files):
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (folder / name.replace("_", ".", 1)).write_text(text)


def test_cgroup_v2_limits_of_the_group_and_its_ancestors_are_counted(tmp_path):
    root = tmp_path / "cgroup"
    _group(root / "user.slice", memory_max=str(2 * GIB), memory_current=str(GIB // 2))
    _group(root / "user.slice" / "job", memory_max="max", memory_current=str(GIB // 4))
    (tmp_path / "membership").write_text("0::/user.slice/job\n")
    assert cgroup_left(tmp_path / "membership", root) == 2 * GIB - GIB // 2
    _group(root / "user.slice" / "job", memory_max=str(GIB), memory_current=str(GIB // 4))
    assert cgroup_left(tmp_path / "membership", root) == GIB - GIB // 4


def test_cgroup_v1_limit_and_no_limit(tmp_path):
    root = tmp_path / "cgroup"
    _group(root / "memory" / "docker" / "abc", memory_limit_in_bytes=str(3 * GIB),
           memory_usage_in_bytes=str(GIB))
    _group(root / "memory" / "docker", memory_limit_in_bytes=str(2 ** 63 - 4096), memory_usage_in_bytes="0")
    (tmp_path / "membership").write_text("12:cpu,cpuacct:/docker/abc\n4:memory:/docker/abc\n")
    assert cgroup_left(tmp_path / "membership", root) == 2 * GIB
    (tmp_path / "membership").write_text("0::/\n")
    assert cgroup_left(tmp_path / "membership", root) is None


def test_a_run_beyond_ulimit_v_is_refused_before_it_starts_naming_the_limit(tmp_path):
    def limited():
        resource.setrlimit(resource.RLIMIT_AS, (3_000_000 * 1024, resource.RLIM_INFINITY))  # ulimit -v 3000000

    out = tmp_path / "run"
    command = [sys.executable, "-m", "quadcosim.main", "run", "tp", "--set", "duration=3600", "bench_supply=on",
               "--out", str(out)]
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, preexec_fn=limited, timeout=300,
                          env=os.environ | {"PYTHONWARNINGS": "ignore"})
    assert done.returncode == 2, done.stderr[-2000:]
    assert "this run would record 3600001 samples of 126 signals, 3.63 GB" in done.stderr
    assert "(bound by ulimit -v)" in done.stderr and "--stream" in done.stderr
    assert "MemoryError" not in done.stderr and not out.exists()


@pytest.mark.parametrize("formats, compress, share", [(("npz",), False, 0.05), (("mat",), False, 0.25),
                                                     (("npz", "mat"), True, 0.5)])
def test_the_writers_peak_stays_within_its_estimate(tmp_path, formats, compress, share):
    """The estimate bounds what the writers allocate at their peak, and is not far above it
    (measured: 0.11, 0.32 and 0.63 of it)."""
    import scipy.io  # noqa: F401 (imported before the memory is traced)

    blocks = {"IMU": ["acc", "gyro", "magneto"], "Quadrotor": ["q", "omega", "p", "v", "R"]}
    names = [f"{block}.{vector}{axis}" for block, vectors in blocks.items() for vector in vectors
             for axis in (["_11", "_12", "_13", "_21", "_22", "_23", "_31", "_32", "_33"] if vector == "R"
                          else ["_x", "_y", "_z"])]
    rows = 200001
    record = Result(np.arange(float(rows)), names, np.random.default_rng(0).random((rows, len(names))))
    widest = max(len(m) for m in vector_groups(names).values())
    largest = max(Counter(n.partition(".")[0] for n in names).values())
    tracemalloc.start()
    try:
        record.save(tmp_path, formats=formats, compress=compress)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    estimate = writers_peak(rows, widest, formats, compress, largest)
    assert share * estimate < peak <= estimate, (peak, estimate)
