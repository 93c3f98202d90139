"""numba's cache of the project's code follows every source it was compiled from
(:mod:`quadcosim.infra.numba_cache`): an edit of a callee in another module reaches the caller's
next run, and earlier sources find their folder again.

numba's own cache is invalidated by the edit of the cached function's own file only. A tiny
package in the test's folder, with the project's pattern (a compiled caller in one module, its
compiled callee in another), is run by fresh processes through the project's locator.
"""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

from quadcosim.infra import numba_cache

# a fresh process: the package in argv[1] keyed as the project's floors are, its result and
# whether the caller came from the cache
PROBE = textwrap.dedent("""
    import sys
    from pathlib import Path
    from quadcosim.infra import numba_cache
    numba_cache.ROOT, numba_cache.FLOORS = Path(sys.argv[1]), ("mini",)
    numba_cache.install()
    sys.path.insert(0, sys.argv[1])
    from mini.caller import twice
    print(twice(), twice.stats.cache_hits.most_common(1) != [])
""")

CALLER = """
from numba import njit

from mini.callee import value


@njit(cache=True)
def twice():
    return 2.0 * value()
"""


def _callee(root: Path, value: float) -> None:
    (root / "mini" / "callee.py").write_text(
        f"from numba import njit\n\n\n@njit(cache=True)\ndef value():\n    return {value!r}\n")


def _run(root: Path, build: Path, **env) -> tuple[float, bool]:
    environment = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    environment.update(QUADCOSIM_BUILD_DIR=str(build), **env)
    done = subprocess.run([sys.executable, "-c", PROBE, str(root)], capture_output=True, text=True,
                          env=environment, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    result, cached = done.stdout.split()
    return float(result), cached == "True"


def test_an_edit_of_the_callee_reaches_the_caller(tmp_path):
    root, build = tmp_path / "src", tmp_path / "build"
    (root / "mini").mkdir(parents=True)
    (root / "mini" / "__init__.py").write_text("")
    (root / "mini" / "caller.py").write_text(CALLER)
    _callee(root, 1.0)
    assert _run(root, build) == (2.0, False)  # compiled
    assert _run(root, build) == (2.0, True)  # loaded from the cache
    _callee(root, 3.0)  # the callee's module only: numba's own cache would serve 2.0
    assert _run(root, build) == (6.0, False)
    _callee(root, 1.0)  # the earlier sources: their folder again, nothing compiled
    assert _run(root, build) == (2.0, True)
    assert len(list((build / "numba").glob("mini-*"))) == 2


def test_a_users_numba_cache_dir_is_left_to_numba(tmp_path):
    root, build = tmp_path / "src", tmp_path / "build"
    (root / "mini").mkdir(parents=True)
    (root / "mini" / "__init__.py").write_text("")
    (root / "mini" / "caller.py").write_text(CALLER)
    _callee(root, 1.0)
    assert _run(root, build, NUMBA_CACHE_DIR=str(tmp_path / "own")) == (2.0, False)
    assert not (build / "numba").exists() and any((tmp_path / "own").rglob("*.nbi"))


def test_the_folders_of_old_sources_are_pruned(tmp_path):
    folders = [tmp_path / f"mini-{k:016x}" for k in range(numba_cache.KEEP + 3)]
    for age, folder in enumerate(folders):
        folder.mkdir()
        os.utime(folder, (1e9 - age, 1e9 - age))  # folders[0] the most recently used
    (tmp_path / "other-0000000000000000").mkdir()  # another package's: not counted
    numba_cache._prune(folders[0], "mini")
    kept = sorted(p.name for p in tmp_path.iterdir())
    assert kept == sorted([f.name for f in folders[:numba_cache.KEEP]] + ["other-0000000000000000"])


def test_the_digest_follows_every_file_of_the_package_and_the_floors_below(tmp_path):
    def digests():  # as after numba comes back to a module (a reload): the files looked at again
        numba_cache._fresh.clear()
        return {p: numba_cache.source_digest(p, tmp_path) for p in ("fmus", "estimators", "calibration")}

    for package in ("fmus", "estimators", "scenarios"):
        (tmp_path / package).mkdir()
        (tmp_path / package / "a.py").write_text("x = 1\n")
    before = digests()
    (tmp_path / "fmus" / "a.py").write_text("x = 20\n")  # a constant a compiled function may read
    after = digests()
    assert all(before[p] != after[p] for p in before)
    (tmp_path / "scenarios" / "a.py").write_text("x = 300\n")  # a floor above: no recompilation below it
    assert digests() == after
