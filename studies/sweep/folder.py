"""What a sweep (or a tune) checks before it writes anything: its folder and its scheduler's address.

- :func:`check_out`: the ``--out`` folder can be made and written (not a file, a dangling
  symlink, a symlink loop, or a read-only place);
- :func:`check_scheduler`: a scheduler's address is one a client in another process can reach
  (``tcp://HOST:PORT``), said before anything is written or a connection tried;
- :func:`held`: the folder made if need be and held by this process (the output folder lock of
  ``quadcosim run``, :func:`quadcosim.infra.files.folder_lock`) while the sweep writes it; a sweep
  refused before it wrote anything leaves no folder behind.
"""

from __future__ import annotations

import contextlib
import errno
import os
from pathlib import Path

from quadcosim.infra.errors import UsageError


class FolderRefused(UsageError, ValueError):
    """The sweep's folder or scheduler address is refused; nothing was written. The message names
    the path or address and the fix."""


def check_out(out: Path, flag: str = "--out") -> Path:
    """Refuse a sweep folder that cannot be made or written, naming why; return ``out``.

    Parameters
    ----------
    out : pathlib.Path
        The folder.
    flag : str
        How the command line names it, in the messages.

    Raises
    ------
    FolderRefused
        ``out`` is a file, a dangling symlink, a symlink loop, a read-only folder, or in a place
        where no folder can be made.
    """
    if out.exists() and not out.is_dir():
        raise FolderRefused(f"{flag} {out}: a file of that name exists; give a folder name")
    existing = out
    while not existing.exists():
        if existing.is_symlink():  # a link that leads nowhere, at the folder or above it
            _broken_link(existing, out, flag)
        if existing.parent == existing:
            break
        existing = existing.parent
    if existing.exists() and not existing.is_dir():
        raise FolderRefused(f"{flag} {out}: {existing} is a file, so no folder can be made under it; give "
                            "another folder")
    if not os.access(existing, os.W_OK | os.X_OK):
        what = "the folder is not writable" if existing == out else f"{existing}/ is not writable"
        raise FolderRefused(f"{flag} {out}: {what}; choose another place")
    return out


def _broken_link(link: Path, out: Path, flag: str):
    """Refuse ``out`` for the symbolic link ``link`` (``out`` or one above it) that leads nowhere."""
    where = "a " if link == out else f"{link} (above it) is a "
    try:
        os.stat(link)
    except OSError as error:
        if error.errno == errno.ELOOP:
            raise FolderRefused(f"{flag} {out}: {where}symbolic link that leads back to itself (a loop); "
                                "remove it or give another folder") from None
    raise FolderRefused(f"{flag} {out}: {where}symbolic link to {os.readlink(link)}, which does not exist; "
                        "create that folder, remove the link, or give another folder")


#: Schemes of a Dask scheduler that a client in another process reaches.
SCHEMES = ("tcp", "tls", "ws", "wss", "ucx")


def check_scheduler(address: str | None) -> str | None:
    """Refuse a scheduler address no client of this process could reach, naming the fix; return it.

    Parameters
    ----------
    address : str or None
        ``tcp://HOST:PORT`` as ``dask scheduler`` prints it (None: a local cluster).

    Raises
    ------
    FolderRefused
        An address without a scheme, host or port; ``inproc://`` (a scheduler inside this very
        process); a scheme Dask does not know; ``tls://`` or ``wss://`` without the client's
        certificates in Dask's configuration.
    """
    if address is None:
        return None
    from distributed.comm.addressing import parse_address, parse_host_port

    example = "give tcp://HOST:PORT, as `dask scheduler` prints it"
    try:
        scheme, location = parse_address(address, strict=True)
    except ValueError:
        raise FolderRefused(f"--scheduler {address!r} is not a scheduler's address: {example}") from None
    if scheme == "inproc":
        raise FolderRefused(f"--scheduler {address}: inproc:// reaches only a scheduler inside this same process, "
                            f"never one started apart; {example}")
    if scheme not in SCHEMES:
        raise FolderRefused(f"--scheduler {address}: Dask has no transport {scheme!r} (it knows "
                            f"{', '.join(SCHEMES)}); {example}")
    try:
        host, port = parse_host_port(location)
    except ValueError:
        host, port = location, None
    if not host or not port:
        raise FolderRefused(f"--scheduler {address}: no {'host' if not host else 'port'} in it; {example}")
    if scheme in ("tls", "wss"):
        import dask

        if not dask.config.get("distributed.comm.tls.client.cert", None):
            raise FolderRefused(f"--scheduler {address}: {scheme}:// needs this client's TLS certificate and key in "
                                "Dask's configuration (distributed.comm.tls.client.cert, .key and "
                                "distributed.comm.tls.ca-file); set them, or use tcp://")
    return address


@contextlib.contextmanager
def held(out: Path, command: str | None = None):
    """Make the folder ``out`` if need be and hold it for this process while the block runs.

    A second sweep (or run) into ``out`` is refused at once, naming this one. When the block ends
    with ``out`` empty (a sweep refused before it wrote anything), the folders this call made
    are removed: a refused sweep leaves nothing.

    Parameters
    ----------
    out : pathlib.Path
        The folder (checked with :func:`check_out`).
    command : str, optional
        What this process is doing, named to a process refused.

    Raises
    ------
    FolderRefused
        The folder cannot be made.
    quadcosim.infra.files.FolderBusy
        Another live process holds the folder (a ValueError naming its pid and command).
    """
    from quadcosim.infra.files import FolderBusy, folder_lock

    made = []  # the folders this call creates, the outermost first
    missing = out
    while not missing.exists() and missing.parent != missing:
        made.insert(0, missing)
        missing = missing.parent
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise FolderRefused(f"--out {out}: cannot create the folder ({error.strerror}); choose another "
                            "place") from None
    try:
        try:
            with folder_lock(out, command):
                yield out
        except FolderBusy as error:
            raise FolderBusy(f"--out {error}") from None
    finally:
        for folder in reversed(made):
            try:
                folder.rmdir()  # only when empty: what a sweep wrote is never removed
            except OSError:
                break
