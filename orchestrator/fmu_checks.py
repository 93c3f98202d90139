"""The checks an FMU file passes before it runs: each refusal names the problem and the fix.

Before anything is extracted or loaded (:func:`check_file`): the archive (no entry outside its
folder, an extracted size and a compression ratio within limits), the model identifier (a
plain file name), a binary for this platform and machine, and the value references of the
variables the master wires (no two inputs on one, no output aliasing an input or a parameter).
At the start (:func:`refused_at_start`): an instance the FMU refuses to make, a missing FMI
function. After the set-up (:func:`probe`): every wired variable can be read. A refusal is a
:class:`FMURefused`, a ``ValueError``: the command line answers it with exit 2.
"""

from __future__ import annotations

import platform
import re
import zipfile
from pathlib import Path, PurePosixPath

from quadcosim.infra.errors import UsageError

#: Extraction limits: the size of everything an FMU holds once extracted, and the ratio of that
#: size to the file's (a zip bomb expands a few MB into GB).
EXTRACT_LIMIT_BYTES = 1 << 30
RATIO_LIMIT = 200
RATIO_FREE_BYTES = 64 << 20  # below this extracted size no ratio is refused

PLATFORM = "linux64"
_MACHINES = {62: "x86_64", 183: "aarch64", 3: "i386", 40: "arm", 243: "riscv64", 21: "ppc64"}
_HOST = {"x86_64": 62, "amd64": 62, "aarch64": 183, "arm64": 183}.get(platform.machine().lower(), 62)


_passed: set[tuple] = set()  # FMU files (path, modification time, size) that passed check_file


class FMURefused(UsageError, ValueError):
    """An FMU the master will not run, for the reason (and the fix) its message gives."""


def check_file(path: Path, description) -> None:
    """Refuse an FMU file whose archive, binary or variables cannot run safely.

    Parameters
    ----------
    path : pathlib.Path
        The ``.fmu`` file.
    description : fmpy.model_description.ModelDescription
        Its model description.

    Raises
    ------
    FMURefused
        What is wrong and how to fix it.
    """
    stat = path.stat()
    key = (str(path), stat.st_mtime_ns, stat.st_size)
    if key in _passed:
        return
    check_archive(path)
    identifier = description.coSimulation.modelIdentifier
    check_identifier(path, identifier)
    check_binary(path, identifier, 3 if str(description.fmiVersion).startswith("3.") else 2)
    check_references(path, description)
    _passed.add(key)


def check_archive(path: Path) -> None:
    """Refuse an archive with an entry that leaves its folder, or that expands beyond the
    limits :data:`EXTRACT_LIMIT_BYTES` and :data:`RATIO_LIMIT` (read from its directory,
    before anything is extracted; the extraction reads no more than the sizes listed).

    Parameters
    ----------
    path : pathlib.Path
        The ``.fmu`` file.
    """
    with zipfile.ZipFile(path) as archive:
        entries = archive.infolist()
    for entry in entries:
        name = entry.filename
        parts = PurePosixPath(name.replace("\\", "/")).parts
        if name.startswith(("/", "\\")) or ".." in parts or ":" in name or "\\" in name:
            raise FMURefused(f"{path.name} holds the entry {name!r}, which would be written outside the folder the "
                             "FMU is extracted to (a zip-slip path): the FMU is refused; export it again with "
                             "plain relative paths")
    total = sum(entry.file_size for entry in entries)
    size = max(path.stat().st_size, 1)
    if total > EXTRACT_LIMIT_BYTES:
        raise FMURefused(f"{path.name} would expand to {total / 2**20:.0f} MiB, over the extraction limit of "
                         f"{EXTRACT_LIMIT_BYTES / 2**20:.0f} MiB: it is refused before extracting (a zip bomb, or "
                         "resources that belong outside the FMU)")
    if total > RATIO_FREE_BYTES and total / size > RATIO_LIMIT:
        raise FMURefused(f"{path.name} would expand {total / size:.0f} times ({size / 2**20:.1f} MiB to "
                         f"{total / 2**20:.0f} MiB), over the extraction limit of {RATIO_LIMIT} times: it is refused "
                         "before extracting (a zip bomb)")


def check_identifier(path: Path, identifier: str) -> None:
    """Refuse a model identifier that is not a plain file name (the binary's name).

    Parameters
    ----------
    path : pathlib.Path
        The ``.fmu`` file.
    identifier : str
        Its ``modelIdentifier``.
    """
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", identifier or ""):
        raise FMURefused(f"{path.name}: its modelIdentifier {identifier!r} is not a plain name (a C identifier, "
                         "the binary's file name without a path): the FMU is refused; export it again with a "
                         "plain model name")


def platform_folder(fmi_version: int) -> str:
    """The ``binaries/`` folder of this machine's Linux binary.

    Parameters
    ----------
    fmi_version : {2, 3}
        The FMU's FMI version.

    Returns
    -------
    str
        ``linux64`` in FMI 2.0, ``x86_64-linux`` (``aarch64-linux`` on an ARM machine) in FMI 3.0.
    """
    return PLATFORM if fmi_version == 2 else f"{_MACHINES[_HOST]}-linux"


def check_binary(path: Path, identifier: str, fmi_version: int = 2) -> None:
    """Refuse an FMU without a binary this machine can load: none for this platform
    (:func:`platform_folder`), or one for another processor. Read from the archive, before
    anything is extracted or loaded.

    Parameters
    ----------
    path : pathlib.Path
        The ``.fmu`` file.
    identifier : str
        Its ``modelIdentifier``: the binary's name.
    fmi_version : {2, 3}
        Its FMI version, which names the platform folders.
    """
    folder = platform_folder(fmi_version)
    with zipfile.ZipFile(path) as archive:
        names = archive.namelist()
        platforms = sorted({n.split("/")[1] for n in names if n.startswith("binaries/") and n.count("/") >= 2
                            and n.split("/")[2]})
        binary = f"binaries/{folder}/{identifier}.so"
        if binary not in names:
            if folder in platforms:
                raise FMURefused(f"{path.name}: its {folder} folder has no {identifier}.so (the binary the "
                                 "modelIdentifier names): export it again for Linux")
            has = (f"it has {', '.join(platforms)}" if platforms
                   else "it has sources only" if any(n.startswith("sources/") for n in names) else "it has none")
            raise FMURefused(f"this FMU has no {folder} binary ({has}): export it for Linux ({path.name})")
        with archive.open(binary) as file:
            header = file.read(20)
    if len(header) < 20 or header[:4] != b"\x7fELF":
        raise FMURefused(f"{path.name}: {binary} is not a Linux shared library (no ELF header): export it for Linux")
    machine = int.from_bytes(header[18:20], "little" if header[5] == 1 else "big")
    if header[4] != 2 or machine != _HOST:
        built = _MACHINES.get(machine, f"machine {machine}") + ("" if header[4] == 2 else ", 32-bit")
        raise FMURefused(f"{path.name}: its {folder} binary is built for {built}; this machine runs "
                         f"{_MACHINES[_HOST]}: export it for {_MACHINES[_HOST]} Linux")


def check_references(path: Path, description) -> None:
    """Refuse value references that make the wiring lie: two inputs on one, an output on the
    reference of an input or a parameter (it would read back what the master set, not what
    the model computes).

    Parameters
    ----------
    path : pathlib.Path
        The ``.fmu`` file.
    description : fmpy.model_description.ModelDescription
        Its model description.
    """
    by_ref: dict[tuple[str, int], list] = {}
    for variable in description.modelVariables:
        by_ref.setdefault((variable.type, variable.valueReference), []).append(variable)
    for (kind, ref), variables in by_ref.items():
        if len(variables) < 2:
            continue
        inputs = [v.name for v in variables if v.causality in ("input", "parameter")]
        outputs = [v.name for v in variables if v.causality == "output"]
        if len(inputs) > 1:
            raise FMURefused(f"{path.name}: {', '.join(inputs)} share the value reference {ref} ({kind}): setting one "
                             "sets the others; the model description is wrong, export it again")
        if inputs and outputs:
            raise FMURefused(f"{path.name}: the output {outputs[0]} has the value reference {ref} of "
                             f"{inputs[0]} ({kind}), so it would read back the value set, not one the model computes; "
                             "the model description is wrong, export it again")


def refused_at_start(error: Exception, name: str, path: Path) -> FMURefused | None:
    """The refusal for an error the FMU's set-up raised, or None for an error of another kind.

    Parameters
    ----------
    error : Exception
        What :class:`quadcosim.orchestrator.fmu.FMUInstance` raised.
    name : str
        The block.
    path : pathlib.Path
        The FMU file.
    """
    text = str(error)
    function = getattr(error, "function", None)  # an quadcosim.orchestrator.fmu.FMUError
    if function in ("fmi2Instantiate", "fmi3InstantiateCoSimulation"):
        logged = "; ".join(error.log[-5:]) or "it logged nothing"
        return FMURefused(f"{name}: {path.name} refused to make an instance ({function} returned NULL; "
                          f"{logged}). Check its GUID and resources, or run it in fmpy to see why")
    missing = re.search(r"undefined symbol: (\w+)", text)
    if isinstance(error, AttributeError) and missing:
        version = "3.0" if missing.group(1).startswith("fmi3") else "2.0"
        return FMURefused(f"{name}: {path.name}'s binary has no function {missing.group(1)}, which FMI {version} "
                          f"Co-Simulation requires: export it again for FMI {version} Co-Simulation")
    if "Failed to load shared library" in text or "Cannot find shared library" in text:
        return FMURefused(f"{name}: {path.name}'s binary cannot be loaded: {text}. Export it for this machine")
    return None


def probe(instance, names) -> None:
    """Read every wired variable once after the set-up: an FMU that refuses a value reference
    it declares is refused before the loop.

    Parameters
    ----------
    instance : quadcosim.orchestrator.fmu.FMUInstance
        Initialized.
    names : sequence of str
        The inputs and outputs the master wires (signal names, of any numeric type).

    Raises
    ------
    FMURefused
        A value reference the FMU does not know, named.
    """
    for name in names:
        try:
            instance.get([name])
        except RuntimeError as error:  # quadcosim.orchestrator.fmu.FMUError (imported by fmu, which imports this)
            if not hasattr(error, "status"):
                raise
            if getattr(instance, "_proxy", None) is not None and instance._proxy.failure:
                raise
            logged = "; ".join(error.log[-3:]) or "it logged nothing"
            raise FMURefused(f"{instance.name}: {instance.path.name} refuses to read {name} (value reference "
                             f"{instance.signal[name].variable.valueReference}, {error.function} returned "
                             f"{error.status}: {logged}): the value references of its model description are "
                             "out of the model's range; export it again") from None
