"""One registry per closed set of names: a dummy member added as a maintainer would add one, a
file (``tests/registry_dummies/``) and one registry line, is seen everywhere the set is read.

Each test runs a fresh interpreter that adds the registry line before anything reads the
registry, exactly as the line would stand in the registry's module, then drives the command line.
"""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DUMMIES = Path(__file__).resolve().parent / "registry_dummies"


def installed_member(site: Path, group: str, line: str) -> Path:
    """A third-party package's registration, as pip leaves it: a ``dummy-members`` distribution in
    ``site`` whose ``entry_points.txt`` holds ``line`` in ``group`` (the one registry line a
    member takes, in its package's ``pyproject.toml``); ``site`` goes on ``sys.path``."""
    record = site / "dummy_members-0.1.dist-info"
    record.mkdir(parents=True, exist_ok=True)
    (record / "METADATA").write_text("Metadata-Version: 2.1\nName: dummy-members\nVersion: 0.1\n")
    points = record / "entry_points.txt"
    points.write_text((points.read_text() if points.is_file() else "") + f"[{group}]\n{line}\n\n")
    return site


def _with_member(group: str, line: str, body: str, tmp_path: Path) -> dict:
    """Run ``body`` with a dummy member registered by ``line`` in the entry-point ``group``."""
    site = installed_member(tmp_path / "site", group, line)
    return _with_line(f"sys.path.insert(0, {str(site)!r})", body, tmp_path)


def _with_line(registry_line: str, body: str, tmp_path: Path) -> dict:
    """Run ``body`` after ``registry_line`` in a fresh interpreter (the dummies importable, the
    working folder ``tmp_path``); what ``body`` leaves in ``found`` (a dict)."""
    script = "\n".join([
        "import contextlib, io, json, sys",
        f"sys.path[:0] = [{str(DUMMIES)!r}, {str(ROOT)!r}]",
        textwrap.dedent(registry_line),
        "found = {}",
        "def cli(*argv):",
        "    from quadcosim.main import main",
        "    out = io.StringIO()",
        "    with contextlib.redirect_stdout(out):",
        "        code = main(list(argv))",
        "    return code, out.getvalue()",
        textwrap.dedent(body),
        "print(json.dumps(found))",
    ])
    done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_a_dummy_estimator_is_one_file_and_one_line(tmp_path):
    found = _with_member("quadcosim.estimators", "gyro-only = dummy_estimator:KIND", '''
        code, listing = cli("list")
        found["listed"] = [line for line in listing.splitlines() if line.strip().startswith("estimator ")][0]
        code, _ = cli("run", "tp", "--set", "estimator=gyro-only", "--set", "duration=0.2", "--out", "out")
        metrics = json.load(open("out/metrics.json"))
        found["ran"] = [code, metrics["options"]["estimator"], metrics["rms_error_deg"]]
        import quadcosim.scenarios, quadcosim.studies.lab_matrix, quadcosim.studies.metge
        from quadcosim.scenarios.flightlog import replay
        found["choices"] = list(quadcosim.scenarios.get("tp").options["estimator"].choices)
        found["compared"] = [list(quadcosim.studies.lab_matrix.COMPARED),
                             list(quadcosim.studies.metge.STUDY_ESTIMATORS)]
        found["replayed"] = list(replay.ESTIMATORS)
        from quadcosim.scenarios.registries import estimator_rows
        found["documented"] = [row for row in estimator_rows() if row[0] == "`gyro-only`"]
        code, parameters = cli("list", "--parameters", "Quaternion_estim")
        found["parameters"] = [line.strip() for line in parameters.splitlines() if "gyro-only" in line]
        from quadcosim.estimators import kinds
        found["bias"] = list(kinds.with_bias())
    ''', tmp_path)
    assert "|gyro-only)" in found["listed"]  # quadcosim list: tp's estimator choices
    assert found["ran"][:2] == [0, "gyro-only"] and found["ran"][2]  # run and scored
    assert found["choices"][-1] == "gyro-only"
    assert all(compared[-1] == "gyro-only" for compared in found["compared"])  # the comparisons run it
    assert "gyro-only" not in found["replayed"]  # a block alone: no batch path for recorded arrays
    # the docs' table (docs/_generated/registries.md): closed loop, no batch path, its own block
    assert found["documented"] == [["`gyro-only`", "gyro only", "", "", "yes", "", "yes", "`dummy_estimator:GyroOnly`"]]
    assert found["parameters"] == ["gyro-only: its own block (dummy_estimator:GyroOnly), its parameters its own"]
    assert found["bias"] == ["explicit", "passive"]  # no gyro-bias estimate: not scored as one


def test_an_estimator_line_that_names_no_kind_is_refused_with_its_fix(tmp_path):
    """A registry line naming the block class instead of its Kind, or a Kind of another name."""
    lines = "gyro-only = dummy_estimator:GyroOnly\nother = dummy_estimator:KIND"
    found = _with_member("quadcosim.estimators", lines, '''
        from quadcosim.estimators import kinds
        try:
            kinds.registry()
        except kinds.EstimatorRegistrationError as error:
            found["error"] = [str(error), isinstance(error, ValueError)]
    ''', tmp_path)
    message, is_value_error = found["error"]
    assert is_value_error and "quadcosim.estimators gyro-only = 'dummy_estimator:GyroOnly'" in message
    assert "registered by dummy-members" in message and "point the line at the module's Kind(\"gyro-only\"" in message


def test_a_dummy_calibration_model_is_one_file_and_one_line(tmp_path):
    from tests.flightlog_synthetic import write_log

    log = tmp_path / "flight.bin"
    write_log(log, duration=40.0)
    found = _with_line('''
        from quadcosim.calibration.flight import catalogue
        from dummy_model import Nothing
        catalogue.MODELS["nothing"] = catalogue.Model("nothing", lambda fitted: Nothing(), preference=5)
    ''', '''
        code, _ = cli("calibrate", "flight.bin", "--out", "out")
        metrics = json.load(open("out/metrics.json"))
        found["default"] = [code, sorted(metrics["models"])]
        code, _ = cli("calibrate", "flight.bin", "--models", "nothing", "current", "--out", "chosen")
        metrics = json.load(open("chosen/metrics.json"))
        found["chosen"] = [code, sorted(metrics["models"]), metrics["models"]["nothing"]["explained_test"]]
        from quadcosim.calibration.flight import catalogue
        found["orders"] = [list(catalogue.preferred("in_file")), list(catalogue.preferred("autopilot"))]
        from quadcosim.scenarios.registries import model_rows
        found["documented"] = [row[0] for row in model_rows()]
    ''', tmp_path)
    assert found["default"][0] == 0 and "nothing" in found["default"][1]  # --models' default: every model
    assert found["chosen"][:2] == [0, ["current", "nothing"]] and abs(found["chosen"][2]) < 1e-9
    assert "nothing" not in found["orders"][0] + found["orders"][1]  # neither the file nor an autopilot carries it
    assert found["documented"][-2:] == ["`dynamic`", "`nothing`"]  # the docs' table, by its rank


def test_a_dummy_scenario_is_one_file_and_one_line(tmp_path):
    found = _with_member("quadcosim.scenarios", "dummy = dummy_scenario", '''
        code, listing = cli("list")
        found["listed"] = [line for line in listing.splitlines() if line.startswith("dummy:")]
        code, _ = cli("run", "dummy", "--set", "duration=0.3", "--out", "out")
        found["ran"] = [code, json.load(open("out/metrics.json"))["final_time_s"]]
        from quadcosim import scenarios
        found["names"] = list(scenarios.names())
        from quadcosim.scenarios.registries import scenario_rows
        found["documented"] = [row for row in scenario_rows() if row[0] == "`dummy`"]
    ''', tmp_path)
    assert found["listed"] == ["dummy: a clock alone"]
    assert found["ran"][0] == 0 and abs(found["ran"][1] - 0.3) < 1e-9
    assert {"dummy", "gain-study"} <= set(found["names"])
    assert found["documented"] == [["`dummy`", "a clock alone", "`dummy_scenario`"]]  # the docs' table


# --- the maintainers' checklists (docs/guides/maintainers.md) -------------------------------

CHECKLISTS = ROOT / "docs" / "guides" / "maintainers.md"


def _section(title: str) -> str:
    text = CHECKLISTS.read_text()
    start = text.index(f"## {title}\n")
    end = text.find("\n## ", start + 1)
    return text[start:end if end > 0 else None]


def _paths(section: str) -> list[str]:
    """The repository paths a checklist names (in backquotes, with a folder)."""
    import re

    return [p for p in re.findall(r"`([\w<>./-]+/[\w<>./-]+)`", section) if "." in p.rsplit("/", 1)[-1]]


def test_every_file_a_checklist_names_exists():
    """``<Model>`` stands for each plant model; a path of the new member's own name is skipped."""
    from quadcosim.fmus import MODELS

    missing = []
    for path in _paths(CHECKLISTS.read_text()):
        if "<name>" in path:
            continue
        for model in MODELS if "<Model>" in path else [None]:
            concrete = path.replace("<Model>", model) if model else path
            if not (ROOT / concrete).exists():
                missing.append(concrete)
    assert missing == []


def test_the_fmu_checklist_names_what_the_build_and_the_tests_require():
    from quadcosim.fmus import MODELS

    section = _paths(_section("Adding a sensor FMU"))
    for required in ("fmus/<Model>/model.c", "fmus/<Model>/variables.py", "fmus/<Model>/__init__.py",
                     "fmus/models.py", "fmus/QuadCoSim/<Model>.mo", "fmus/QuadCoSim/package.order",
                     "tests/test_variable_tables.py", "docs/guides/fmus.md"):
        assert required in section, required
    build = (ROOT / "fmus" / "build.py").read_text()
    assert 'HERE / model / "model.c"' in build  # what the build compiles of a model
    assert 'f"quadcosim.fmus.{model}.variables"' in (ROOT / "fmus" / "models.py").read_text()  # its table
    from tests.test_variable_tables import INPUTS

    order = (ROOT / "fmus" / "QuadCoSim" / "package.order").read_text().split()
    table = (ROOT / "docs" / "guides" / "fmus.md").read_text()
    for model in MODELS:  # each step, done for every model there is
        assert model in order and model in INPUTS and f"| `{model}` |" in table, model


def _the_estimator_checklist_is_how_every_estimator_stands(checklist: str):
    """Each registered estimator is a module's ``KIND`` named by one line of ``pyproject.toml``, as
    the checklist's line shows; each filter of the compiled core is in ``COMPILED``, with its code."""
    import tomllib

    from quadcosim.estimators import core, kinds

    assert '`<name> = "quadcosim.estimators.<name>:KIND"`' in checklist and "`COMPILED`" in checklist
    lines = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["entry-points"][kinds.GROUP]
    assert list(lines) == list(kinds.registry())  # the lines are the registry, in its order
    for value in lines.values():
        module, _, attribute = value.partition(":")
        assert attribute.endswith("KIND") and module.startswith("quadcosim.estimators."), value
    compiled = {name for name, kind in kinds.registry().items() if kind.code is not None}
    assert compiled == set(core.COMPILED) and len({kind.code for kind in core.COMPILED.values()}) == len(compiled)
    for name in compiled:  # a compiled filter's module is named after it, as the checklist says
        assert (ROOT / "estimators" / f"{name}.py").is_file(), name


def test_the_estimator_and_model_checklists_name_the_registries_the_dummies_extend():
    """The registry line of each dummy test is the one its checklist names."""
    from quadcosim.calibration.flight import catalogue
    from quadcosim.estimators import kinds

    estimator = _section("Adding an estimator")
    assert Path(kinds.__file__).relative_to(ROOT).as_posix() in _paths(estimator)
    assert "estimators/contract.py" in _paths(estimator) and f'`[project.entry-points."{kinds.GROUP}"]`' in estimator
    _the_estimator_checklist_is_how_every_estimator_stands(estimator)
    model = _section("Adding a flight-log model or autopilot")
    assert Path(catalogue.__file__).relative_to(ROOT).as_posix() in _paths(model) and "`MODELS`" in model
    from quadcosim.calibration.flight import autopilot

    assert Path(autopilot.__file__).relative_to(ROOT).as_posix() in _paths(model) and "`AUTOPILOTS`" in model
    scenario = _section("Adding a scenario")
    assert "scenarios/catalogue.py" in _paths(scenario) and "`MODULES`" in scenario
