"""numba's on-disk cache of the project's compiled code, keyed by the sources it was compiled from.

numba reuses a cached function while the file holding it is unchanged: an edit of a function it
calls from another module (``calibration/infrared/detection.py`` called by ``filters.py``), or
of a constant it reads from one (``layout.py``), would go unseen, and the old machine code would
run. :func:`install` registers a cache locator that puts the cache of every function of the
project's packages in ``<build root>/numba/<package>-<digest>/``, where ``<digest>`` is the
SHA-256 of every ``.py`` file of that package and of the packages on the floors below it (the
only ones it may import, ``tests/test_architecture.py``): any edit there starts a fresh
folder, and a run never loads code compiled from other sources. Switching back to earlier
sources finds their folder again; per package the :data:`KEEP` most recently used folders are
kept, older ones deleted when a new one is made.

A user's own ``NUMBA_CACHE_DIR`` is respected (numba's locator then places the cache, keyed by
each function's own file only: that user owns invalidation).
"""

from __future__ import annotations

import hashlib
import os
import shutil
from pathlib import Path

#: The floors that may hold cached numba code, from the ground up (``tests/test_architecture.py``'s
#: order): a function of one of these packages is keyed by its own package and those below.
FLOORS = ("fmus", "orchestrator", "flightlogs", "estimators", "calibration", "flight", "scenarios", "studies")
#: Folders of earlier sources kept per package (the most recently used).
KEEP = 4

_PACKAGE = Path(__file__).resolve().parents[1]
#: The folder holding the floors' folders: the source checkout (``fmus/`` beside ``pyproject.toml``),
#: or the installed ``quadcosim`` package.
ROOT = _PACKAGE.parent if (_PACKAGE.parent / "fmus" / "__init__.py").is_file() else _PACKAGE

_digests: dict[tuple[str, Path], tuple[tuple, bytes]] = {}  # (package, root) -> (stat signature, digest)
_current: dict[str, Path] = {}  # package -> its folder, until numba comes back to a module (a reload)
_fresh: set[tuple[str, Path]] = set()  # packages whose digest has been checked since then
_decorated: set[str] = set()  # the files whose functions numba has decorated in this process
_last_file: list[str | None] = [None]
_relative: dict[str, Path | None] = {}  # a function's file -> its path under ROOT (None: outside)
_used: set[Path] = set()  # folders marked used by this process


def _package_digest(package: str, root: Path) -> bytes:
    """SHA-256 of the relative paths and bytes of the ``.py`` files of one package, re-read only
    when a file's size or modification time (ns) has changed since this process read it."""
    if (package, root) in _fresh:
        return _digests[(package, root)][1]
    files = []
    for folder, subfolders, names in os.walk(root / package):
        subfolders[:] = sorted(s for s in subfolders if s != "__pycache__")
        files += [Path(folder, name) for name in sorted(names) if name.endswith(".py")]
    signature = tuple((path, stat.st_mtime_ns, stat.st_size) for path in files for stat in [path.stat()])
    known = _digests.get((package, root))
    _fresh.add((package, root))
    if known is not None and known[0] == signature:
        return known[1]
    digest = hashlib.sha256()
    for path in files:
        digest.update(path.relative_to(root).as_posix().encode() + b"\0")
        digest.update(path.read_bytes())
    _digests[(package, root)] = (signature, digest.digest())
    return _digests[(package, root)][1]


def source_digest(package: str, root: Path = ROOT) -> str:
    """Digest of the sources numba may compile a function of ``package`` from.

    Parameters
    ----------
    package : str
        One of :data:`FLOORS`.
    root : pathlib.Path
        The folder holding the packages.

    Returns
    -------
    str
        16 hex digits of the SHA-256 of the relative paths and bytes of every ``.py`` file of
        ``package`` and of the floors below it.
    """
    digest = hashlib.sha256()
    for below in FLOORS[:FLOORS.index(package) + 1]:
        digest.update(_package_digest(below, root))
    return digest.hexdigest()[:16]


def cache_root() -> Path:
    """The folder holding the digest-named cache folders: ``numba/`` under the build root
    (:func:`quadcosim.infra.folders.build_root`)."""
    from quadcosim.infra.folders import build_root

    return build_root() / "numba"


def _prune(folder: Path, package: str) -> None:
    """Delete all but the :data:`KEEP` most recently used folders of ``package`` besides ``folder``."""
    try:
        others = [p for p in folder.parent.glob(f"{package}-*") if p != folder and p.is_dir()]
        others.sort(key=lambda p: p.stat().st_mtime, reverse=True)
    except OSError:
        return
    for stale in others[KEEP - 1:]:
        shutil.rmtree(stale, ignore_errors=True)


def _folder(package: str, root: Path) -> Path:
    """The cache folder of ``package``'s present sources, made (older ones pruned) or marked used."""
    if package in _current:
        return _current[package]
    folder = cache_root() / f"{package}-{source_digest(package, root)}"
    if folder not in _used:
        if folder.is_dir():
            os.utime(folder)  # most recently used: kept by the pruning
        else:
            from quadcosim.infra.folders import make_folder

            make_folder(folder, "numba's cache")
            _prune(folder, package)
        _used.add(folder)
    _current[package] = folder
    return folder


def _relative_path(py_file: str) -> Path | None:
    """``py_file``'s path under :data:`ROOT` if it is in a package of :data:`FLOORS`, else None."""
    if py_file not in _relative:
        try:
            relative = Path(py_file).resolve().relative_to(ROOT)
        except ValueError:
            relative = None
        ok = relative is not None and len(relative.parts) > 1 and relative.parts[0] in FLOORS
        _relative[py_file] = relative if ok else None
    return _relative[py_file]


def _locator_class():
    from numba.core import caching, config

    class SourceKeyedLocator(caching._SourceFileBackedLocatorMixin, caching._CacheLocator):
        """numba's cache locator for the functions of :data:`FLOORS`: their package's folder of
        :func:`_folder`, mirroring the source tree (same-named modules stay apart)."""

        def __init__(self, py_func, py_file, path):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            self._cache_path = str(path)

        def get_cache_path(self):
            return self._cache_path

        @classmethod
        def from_function(cls, py_func, py_file):
            if config.CACHE_DIR:  # the user's own folder: numba's locator
                return None
            relative = _relative_path(py_file)
            if relative is None:
                return None
            if _last_file[0] != py_file:
                if py_file in _decorated:  # a module decorated again (reloaded): the sources may have changed
                    _current.clear()
                    _fresh.clear()
                _decorated.add(py_file)
                _last_file[0] = py_file
            path = _folder(relative.parts[0], ROOT) / relative.parent
            self = cls(py_func, py_file, path)
            self.ensure_cache_path()  # not writable: an error, rather than numba's stale-prone fallback
            return self

    return SourceKeyedLocator


_installed: list = []


def install() -> None:
    """Make numba cache the project's compiled functions by their sources (this module's
    docstring); idempotent. Called before any of the project's cached functions is decorated
    (numba chooses a function's cache folder then): by the ``__init__`` of the packages holding
    them, or by the module itself (``tests/test_architecture.py`` checks it)."""
    if _installed:
        return
    from numba.core import caching

    locator = _locator_class()
    impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl
    impl._locator_classes.insert(0, locator)
    _installed.append(locator)
