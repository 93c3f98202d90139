"""How much memory a run may take: the machine's, the process's address-space limit and its
control group's limit, whichever is smallest; and what a record and its writers need.

A record of ``rows`` samples of ``signals`` float64 signals takes ``8 rows signals`` bytes. The
writers add a copy of their largest array at a time (a vector, ``IMU.R_reel`` N x 3 x 3 the
largest), and a compressed ``.mat`` file holds a whole block in memory while it is compressed.
"""

from __future__ import annotations

import functools
import resource
from pathlib import Path

#: A control group's limit at or above this is no limit (cgroup v1 writes 2**63 - 4096).
UNLIMITED = 2 ** 60


def machine_available(meminfo: str = "/proc/meminfo") -> int | None:
    """``MemAvailable`` (bytes): what the kernel can give without swapping; None if unknown.

    Parameters
    ----------
    meminfo : str
        The kernel's memory table.
    """
    try:
        with open(meminfo) as lines:
            for line in lines:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return None


def address_space_left(status: str = "/proc/self/status") -> int | None:
    """Bytes of address space left under ``ulimit -v`` (``RLIMIT_AS``) beyond what the process
    maps already (``VmSize``); None without a limit.

    Parameters
    ----------
    status : str
        The process's status table (its ``VmSize``).
    """
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft == resource.RLIM_INFINITY:
        return None
    mapped = 0
    try:
        with open(status) as lines:
            for line in lines:
                if line.startswith("VmSize:"):
                    mapped = int(line.split()[1]) * 1024
    except OSError:
        pass
    return max(0, soft - mapped)


def cgroup_left(membership: str = "/proc/self/cgroup", root: str = "/sys/fs/cgroup") -> int | None:
    """Bytes the process's control group (v2 ``memory.max``, or v1 ``memory.limit_in_bytes``)
    and each of its ancestors may still take; None without a limit. The process's own groups
    (the default paths) and their limits are read once per process, since a sweep checks every
    member; their usage at every call. Other paths are read whole at every call.

    Parameters
    ----------
    membership : str
        The process's groups, one ``id:controllers:path`` a line (``/proc/self/cgroup``).
    root : str
        Where the control-group hierarchies are mounted (``/sys/fs/cgroup``).
    """
    if (membership, root) == _OWN:
        groups = _own_groups()
    else:
        groups = _limited_groups(membership, root)
    left = [max(0, limit - (_number(usage) or 0)) for usage, limit in groups]
    return min(left) if left else None


_OWN = ("/proc/self/cgroup", "/sys/fs/cgroup")


@functools.cache
def _own_groups() -> tuple[tuple[Path, int], ...]:
    return _limited_groups(*_OWN)


def _limited_groups(membership: str, root: str) -> tuple[tuple[Path, int], ...]:
    """(usage file, limit) of the control group in ``membership`` and of each ancestor with a limit."""
    try:
        lines = Path(membership).read_text().splitlines()
    except OSError:
        return ()
    found = []
    for line in lines:
        number, controllers, path = line.split(":", 2)
        if number == "0" and controllers == "":  # v2, the unified hierarchy
            found += _limits(Path(root), path, "memory.max", "memory.current")
        elif "memory" in controllers.split(","):  # v1
            found += _limits(Path(root) / "memory", path, "memory.limit_in_bytes", "memory.usage_in_bytes")
    return tuple(found)


def _limits(base: Path, path: str, limit_name: str, usage_name: str) -> list[tuple[Path, int]]:
    """(usage file, limit) of the group at ``path`` and of each ancestor that has a limit."""
    found = []
    group = base / path.strip("/")
    while True:
        limit = _number(group / limit_name)
        if limit is not None and limit < UNLIMITED:
            found.append((group / usage_name, limit))
        if group == base or base not in group.parents:
            return found
        group = group.parent


def _number(path: Path) -> int | None:
    try:
        text = path.read_text().strip()
    except OSError:
        return None
    return None if text in ("", "max") else int(text)


def available() -> tuple[int | None, str]:
    """Memory a run may take (bytes) and what sets it.

    Returns
    -------
    (int or None, str)
        The smallest of the machine's available memory, the address space left under
        ``ulimit -v`` and the room left in the control group; and its name
        (``"the machine's MemAvailable"``, ``"ulimit -v"``, ``"the control group's memory limit"``).
        None where none is known.
    """
    found = [(machine_available(), "the machine's MemAvailable"), (address_space_left(), "ulimit -v"),
             (cgroup_left(), "the control group's memory limit")]
    known = [(value, name) for value, name in found if value is not None]
    return min(known) if known else (None, "unknown")


#: Bytes the writers hold whatever the record (buffers, compressor state).
WRITER_BUFFERS = 16 * 2 ** 20


def writers_peak(rows: int, widest: int, formats=("npz",), compress: bool = False, largest_block: int = 0) -> int:
    """Bytes the record's writers take beside the record at their peak.

    Parameters
    ----------
    rows : int
        Samples recorded.
    widest : int
        Components of the widest vector written (9 for ``IMU.R_reel``; 1 without vectors).
    formats : sequence of str
        Formats written (``npz``, ``mat``, ``csv``), one after the other.
    compress : bool
        Compressed ``.npz`` and ``.mat``.
    largest_block : int
        Signals of the block with most signals written (a compressed ``.mat`` holds one block
        at a time, its vectors twice).

    Returns
    -------
    int
        Bytes: twice the widest vector (measured once: the ``.mat`` writer lays it out, a
        compressed ``.npz`` buffers it), :data:`WRITER_BUFFERS`, and for a compressed ``.mat``
        ten times the largest block (its serialised bytes with its vectors, their copy and
        its compressed form: 7.1 to 8.9 times measured).
    """
    peak = 2 * 8 * rows * max(widest, 1) + WRITER_BUFFERS
    if compress and "mat" in formats:
        peak += 10 * 8 * rows * largest_block
    return peak


def in_gigabytes(count: int) -> str:
    """``count`` bytes in GB, three significant digits."""
    return f"{count / 1e9:.3g} GB"


def process_peak() -> int:
    """Peak resident memory of this process so far (bytes, ``ru_maxrss``)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
