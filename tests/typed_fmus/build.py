"""Build the tests' own small FMUs from C (``types2.c``, ``types3.c``) with the system's C compiler:
one FMU per source, its model description beside it, the FMI headers from fmpy's package.

fmpy binds every function of the FMI version when it loads a binary; the functions a model
does not implement are compiled as stubs that return fmi2Error / fmi3Error.
"""

import re
import subprocess
import zipfile
from pathlib import Path

import fmpy

HERE = Path(__file__).resolve().parent
HEADERS = Path(fmpy.__file__).parent / "c-code"


def _stubs(version: int, source: str) -> str:
    """C stubs of the FMI functions the header declares and ``source`` does not define."""
    header = (HEADERS / f"fmi{version}Functions.h").read_text()
    declared = re.findall(rf"FMI{version}_Export\s+\w+TYPE\s+(fmi{version}\w+)\s*;", header)
    defined = set(re.findall(rf"^\w[\w\s\*]*?\b(fmi{version}\w+)\s*\(", source, re.MULTILINE))
    defined |= {f"fmi{version}{m}" for m in re.findall(rf"fmi{version}Get##Type|fmi{version}Set##Type", source)}
    for kind in re.findall(r"^ACCESS\((\w+),", source, re.MULTILINE):
        defined |= {f"fmi{version}Get{kind}", f"fmi{version}Set{kind}"}
    lines = [f"int {name}(void) {{ return 3; }}" for name in declared if name not in defined]
    return "\n".join(lines) + "\n"


def build(model: str, folder: Path, defines: tuple = ()) -> Path:
    """Compile ``model`` (``"types2"`` or ``"types3"``) into ``folder/<Model>.fmu``, with the C
    macros ``defines`` (``("LYING_STEP",)``: a step that returns -1 from t = 0.1 s).

    Returns
    -------
    pathlib.Path
        The FMU file.
    """
    version = int(model[-1])
    identifier = model.capitalize()
    source = (HERE / f"{model}.c").read_text()
    stubs = folder / f"{model}_stubs.c"
    stubs.write_text(_stubs(version, source))
    platform = "x86_64-linux" if version == 3 else "linux64"
    library = folder / f"{identifier}.so"
    subprocess.run(["gcc", "-std=c99", "-O1", "-fPIC", "-shared", "-Wall", "-Werror", f"-I{HEADERS}",
                    *(f"-D{d}" for d in defines),
                    "-o", str(library), str(HERE / f"{model}.c"), str(stubs)], check=True, capture_output=True,
                   text=True)
    path = folder / f"{identifier}.fmu"
    with zipfile.ZipFile(path, "w") as archive:
        archive.write(HERE / f"{model}.xml", "modelDescription.xml")
        archive.write(library, f"binaries/{platform}/{identifier}.so")
    return path
