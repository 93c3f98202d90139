"""No bare numbers in the models, the controller and the estimators.

A literal number must carry a name (a constant, an option, a parameter default, a keyword
argument) or stand in a formula as 0, 1, 2 or 0.5. The other counts every reader knows are
named once here: 3 axes of space, 4 components of a quaternion, 9 entries of a 3 x 3 matrix
(integers only: ``3.0 * x`` is a coefficient and needs a name), and a small integer inside a
subscript (``r[6 + i]``, ``q[3]``: a position inside such a vector or matrix). Anything else
is listed in :data:`EXCEPTIONS` with the formula it belongs to, or named in the code.
"""

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCANNED = ("fmus/*/model.c", "fmus/c/*.c", "fmus/c/*.h", "fmus/*.py", "fmus/*/variables.py",
           "flight/**/*.py", "flight/**/*.c", "estimators/**/*.py", "estimators/**/*.c")
FORMULA = {0, 1, 2, 0.5}  # the only bare numbers of formulas
COUNTS = {3: "axes of space", 4: "components of a quaternion", 9: "entries of a 3 x 3 matrix"}
LARGEST_INDEX = 9  # integer subscripts up to this are positions inside a vector, quaternion or matrix

# Literals that belong to a published formula, by file (the text as written).
EXCEPTIONS = {
    "fmus/MotorMagnetics/model.c": {
        "3.0": "ETDRK4 weight phi1 - 3 phi2 + 4 phi3 (Cox and Matthews, 2002)",
        "4.0": "ETDRK4 weights; the discriminant trace^2 - 4 det of a 2 x 2 matrix",
        "6.0": "RK4 weights h/6; 1/3! of the phi3 series",
    },
    "fmus/c/cosimulation.h": {"6.0": "RK4 weights h/6"},
    "fmus/c/noise.h": {
        "0x9E3779B97F4A7C15ull": "splitmix64 (Steele, Lea and Flood, 2014)",
        "0xBF58476D1CE4E5B9ull": "splitmix64", "0x94D049BB133111EBull": "splitmix64",
        "30": "splitmix64", "27": "splitmix64", "31": "splitmix64",
        "0xD1B54A32D192ED03ull": "a second splitmix64 stream (its golden-ratio-like increment)",
        "11": "64 - 53: the top 53 bits of a hash make a double in [0, 1)",
        "0x1.0p-53": "2^-53, the spacing of doubles in [0.5, 1)",
    },
    "estimators/quaternions.py": {"0.25": "Shepperd's quaternion from a rotation matrix (q_i = s / 4)"},
}

_C_NUMBER = re.compile(r"(?<![\w.])(0[xX][0-9a-fA-F]*(?:\.[0-9a-fA-F]*)?(?:[pP][-+]?\d+)?[uUlL]*"
                       r"|(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?[uUlLfF]*)(?![\w.])")
# the literal initialises an upper-case name (enum member, constant) or a const variable
_C_NAMED = re.compile(r"(\b[A-Z][A-Z0-9_]*|\bconst\b[^;=()]*\b\w+)\s*=\s*-?\s*$")


def _files():
    for pattern in SCANNED:
        yield from sorted(ROOT.glob(pattern))


def _allowed(value, text: str, in_subscript: bool, path: str) -> bool:
    if value in FORMULA and not isinstance(value, bool):
        return True
    if isinstance(value, int) and (value in COUNTS or (in_subscript and 0 <= value <= LARGEST_INDEX)):
        return True
    return text in EXCEPTIONS.get(path, {})


def _c_value(text: str):
    core = text.rstrip("uUlLfF") if not text.lower().startswith("0x") else text
    if core.lower().startswith("0x"):
        return float.fromhex(core.rstrip("uUlL")) if "p" in core.lower() else int(core.rstrip("uUlL"), 16)
    return int(core) if re.fullmatch(r"\d+", core) else float(core)


def _strip_c(text: str) -> str:
    """Comments and string/character literals blanked, line numbers kept."""
    pattern = re.compile(r"/\*.*?\*/|//[^\n]*|\"(?:\\.|[^\"\\])*\"|'(?:\\.|[^'\\])*'", re.S)
    return pattern.sub(lambda m: re.sub(r"[^\n]", " ", m.group()), text)


def c_literals(path: Path, name: str) -> list[str]:
    """Unnamed literals of a C file: ``path:line: literal`` for each."""
    found = []
    for number, line in enumerate(_strip_c(path.read_text()).splitlines(), 1):
        if re.match(r"\s*#\s*(include|if|ifndef|ifdef|endif|else|elif|pragma)\b", line):
            continue
        for match in _C_NUMBER.finditer(line):
            before, text = line[:match.start()], match.group(1)
            if _C_NAMED.search(before) or re.match(r"\s*#\s*define\s", line):
                continue
            depth = before.count("[") - before.count("]")
            if not _allowed(_c_value(text), text, depth > 0, name):
                found.append(f"{name}:{number}: {text}    {line.strip()}")
    return found


def _named_nodes(tree) -> set[int]:
    """ids of the nodes whose literals carry a name."""
    named = set()

    def mark(node):
        named.update(id(sub) for sub in ast.walk(node))

    def constant_name(target) -> bool:
        if isinstance(target, ast.Tuple | ast.List):
            return all(constant_name(t) for t in target.elts)
        return isinstance(target, ast.Name) and target.id.lstrip("_").isupper()

    for node in ast.walk(tree):
        if isinstance(node, ast.Assign) and all(constant_name(t) for t in node.targets):
            mark(node.value)
        elif isinstance(node, ast.AnnAssign) and node.value is not None and constant_name(node.target):
            mark(node.value)
        elif isinstance(node, ast.ClassDef):  # class attributes and dataclass fields are names
            for statement in node.body:
                if isinstance(statement, ast.Assign | ast.AnnAssign) and statement.value is not None:
                    mark(statement.value)
        elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda):
            for default in node.args.defaults + [d for d in node.args.kw_defaults if d is not None]:
                mark(default)
        elif isinstance(node, ast.keyword):
            mark(node.value)
        elif isinstance(node, ast.Dict):
            for key, value in zip(node.keys, node.values, strict=True):
                if isinstance(key, ast.Constant) and isinstance(key.value, str):
                    mark(value)
    return named


def _subscripted(tree) -> set[int]:
    inside = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Subscript):
            inside.update(id(sub) for sub in ast.walk(node.slice))
    return inside


def py_literals(path: Path, name: str) -> list[str]:
    """Unnamed literals of a Python file: ``path:line: literal`` for each."""
    source = path.read_text()
    tree = ast.parse(source)
    named, subscripted = _named_nodes(tree), _subscripted(tree)
    lines = source.splitlines()
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Constant) or isinstance(node.value, bool) \
                or not isinstance(node.value, int | float) or id(node) in named:
            continue
        text = ast.get_source_segment(source, node)
        if not _allowed(node.value, text, id(node) in subscripted, name):
            found.append(f"{name}:{node.lineno}: {text}    {lines[node.lineno - 1].strip()}")
    return found


def literals(path: Path) -> list[str]:
    name = path.relative_to(ROOT).as_posix()
    return c_literals(path, name) if path.suffix in (".c", ".h") else py_literals(path, name)


def test_the_scanner_finds_what_it_should(tmp_path):
    sample = tmp_path / "sample.c"
    sample.write_text('#define LIMIT 64\nenum { A = 3, B = 12 };\nstatic const double TOL = 1e-6;\n'
                      '/* 42 in a comment */ const char *s = "7 in a string";\n'
                      'double f(double x, double r[9]) { return r[6 + 1] * x + 64 * x - 1e-6 + 0.5 * 3.0; }\n')
    found = [line.split("    ")[0] for line in c_literals(sample, "sample.c")]
    assert found == ["sample.c:5: 64", "sample.c:5: 1e-6", "sample.c:5: 3.0"]
    code = ('LIMIT = 64  # named\nA, B = 0.3, 7\nclass C:\n    gain: float = 0.25\n'
            'def f(x, tol=1e-9, r=None):\n    "doc 42"\n'
            '    return r[5] + 3 * x + 1.5 * x + g(x, rtol=1e-3) + {"k": 17}["k"] + 30\n')
    path = tmp_path / "sample.py"
    path.write_text(code)
    found = [line.split("    ")[0] for line in py_literals(path, "sample.py")]
    assert sorted(found) == ["sample.py:7: 1.5", "sample.py:7: 30"]


def test_no_bare_numbers_in_the_models_the_controller_and_the_estimators():
    files = list(_files())
    assert any(f.name == "model.c" for f in files) and any("estimators" in f.parts for f in files)
    found = [line for path in files for line in literals(path)]
    assert not found, ("name these numbers (a constant with its unit, or an entry of EXCEPTIONS with the "
                       "formula they belong to):\n" + "\n".join(found))
