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
    found = _with_line('''
        from quadcosim.estimators import kinds
        kinds.KINDS["gyro-only"] = kinds.Kind("gyro-only", "gyro only", batch=False, block="dummy_estimator:GyroOnly")
    ''', '''
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
    ''', tmp_path)
    assert "|gyro-only)" in found["listed"]  # quadcosim list: tp's estimator choices
    assert found["ran"][:2] == [0, "gyro-only"] and found["ran"][2]  # run and scored
    assert found["choices"][-1] == "gyro-only"
    assert all(compared[-1] == "gyro-only" for compared in found["compared"])  # the comparisons run it
    assert "gyro-only" not in found["replayed"]  # a block alone: no batch path for recorded arrays
    # the docs' table (docs/_generated/registries.md): closed loop, no batch path, its own block
    assert found["documented"] == [["`gyro-only`", "gyro only", "", "", "yes", "", "yes", "`dummy_estimator:GyroOnly`"]]


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


def test_a_dummy_sensor_fmu_is_one_folder_and_one_line(tmp_path):
    """tests/registry_dummies/dummy_sensor/ (a barometer: model.c, variables.py, its twin, its
    checks' data) registered by one entry point: built, listed, in the docs' table, a real FMU that
    validates and runs in a System, and in the FMU checks' tables, which it passes."""
    import os
    import shutil

    from quadcosim.fmus import default_fmu_dir

    fmus = tmp_path / "fmus"  # the FMUs built already, as they are (up to date): the build makes the dummy's
    shutil.copytree(default_fmu_dir(), fmus, ignore=shutil.ignore_patterns("QuadCoSim", ".*"))
    found = _with_member("quadcosim.sensors", "Barometer = dummy_sensor", f"""
        import os
        os.environ["QUADCOSIM_FMU_DIR"] = {str(fmus)!r}
        code, out = cli("build", "--out", {str(fmus)!r})
        found["built"] = [code, [line.split()[0] for line in out.splitlines() if "Barometer" in line]]
        found["twins"] = open({str(fmus / "QuadCoSim" / "package.order")!r}).read().split()
        code, listing = cli("list", "--parameters", "Barometer")
        found["listed"] = [code, listing.splitlines()]
        from fmpy.validation import validate_fmu
        found["problems"] = validate_fmu({str(fmus / "Barometer.fmu")!r})
        from quadcosim import Constant, FMUBlock, System
        system = System(dt=1e-3)
        speeds = dict((f"{{name}}{{n}}", 540.0 * (name == "omega_r")) for name in ("omega_r", "domega_r")
                      for n in range(1, 5))
        system.add(Constant("Rotors", speeds | dict(wind_x=0.0, wind_y=0.0, wind_z=0.0)))
        system.add(FMUBlock("Quadrotor", model="Quadrotor"))
        system.add(FMUBlock("Barometer", model="Barometer", parameters=dict(tau=0.005)))
        for name in [*speeds, "wind_x", "wind_y", "wind_z"]:
            system.connect(f"Rotors.{{name}}", f"Quadrotor.{{name}}")
        system.connect("Quadrotor.p_z", "Barometer.p_z")
        result = system.run(1.0)
        found["climb"] = [float(-result["Quadrotor.p_z"][-1]), float(result["Barometer.altitude"][-1]),
                          float(result["Barometer.pressure"][0] - result["Barometer.pressure"][-1])]
        from quadcosim.scenarios.registries import sensor_rows, tables
        found["documented"] = [list(row) for row in sensor_rows() if row[0] == "`Barometer`"]
        found["page"] = "`dummy_sensor`" in tables()
    """, tmp_path)
    assert found["built"] == [0, ["built", "built"]]  # its FMI 2.0 and 3.0 FMUs, the others up to date
    assert found["twins"][-1] == "Barometer"  # its twin in the Modelica package the build writes
    assert found["listed"][0] == 0 and any(line.split()[:3] == ["tau", "=", "0.02"] for line in found["listed"][1])
    assert found["problems"] == []  # fmpy's validation
    climb, altitude, drop = found["climb"]
    assert climb > 0.5 and altitude == climb  # the Quadrotor climbs (rotors above hover); h0 = 0
    # the standard atmosphere near sea level: dp/dh = -rho g = -1.225 kg/m3 * 9.80665 m/s2 = -12.01 Pa/m
    assert abs(drop / climb - 12.01) < 0.03 * 12.01, drop / climb
    assert found["documented"] == [["`Barometer`", "the measured pressure (1)", "exact (altitude held over a step)",
                                    "—", "`dummy_sensor`"]] and found["page"]
    # the FMU checks iterate the registry, and the dummy passes each with its own data
    env = dict(os.environ, QUADCOSIM_FMU_DIR=str(fmus),
               PYTHONPATH=os.pathsep.join([str(tmp_path / "site"), str(DUMMIES), str(ROOT)]))
    checks = ["tests/test_fmu_reset.py", "tests/test_fmu_packaging.py", "tests/test_fmu_platforms.py",
              "tests/test_variable_tables.py", "tests/test_twins.py"]
    done = subprocess.run([sys.executable, "-m", "pytest", "-v", "-p", "no:cacheprovider", "-k", "Barometer", *checks],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout[-3000:]
    passed = [line.split("::")[0] for line in done.stdout.splitlines() if "[Barometer" in line and " PASSED" in line]
    assert sorted(set(passed)) == sorted(checks) and len(passed) >= 10, done.stdout[-3000:]


def test_a_sensor_registration_that_is_no_sensor_fmu_is_refused_with_the_fix(tmp_path):
    """A registered name other than its table's, and a package without model.c: each refused
    when the model is asked for, the message naming what is wrong and what to do."""
    site = installed_member(tmp_path / "site", "quadcosim.sensors", "Altimeter = dummy_sensor")
    found = _with_member("quadcosim.sensors", "Empty = json", '''
        from quadcosim.fmus.models import SensorError, fmu_sources, model_variables
        for name, ask in (("Altimeter", model_variables), ("Empty", fmu_sources)):
            try:
                ask(name)
            except SensorError as error:
                found[name] = str(error)
    ''', tmp_path)
    assert site == tmp_path / "site"
    assert "TABLE is named 'Barometer'; name it 'Altimeter'" in found["Altimeter"]
    assert "has no model.c nor variables.py" in found["Empty"] and "a sensor FMU is a folder" in found["Empty"]


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
    """The sensor checklist names a model's folder files and its registry line; each model has
    them; each check it names is read by the test file it names, which names no model."""
    import re
    import tomllib

    from quadcosim.fmus.models import CHECKS, GROUP, sensors

    text = _section("Adding a sensor FMU")
    section = _paths(text)
    own = [p for p in section if p.startswith("fmus/<Model>/")]
    assert own == ["fmus/<Model>/model.c", "fmus/<Model>/variables.py", "fmus/<Model>/<Model>.mo",
                   "fmus/<Model>/__init__.py"]  # the folder: everything of the model
    assert f"`{GROUP}`" in text and '`<Model> = "quadcosim.fmus.<Model>"`' in text  # the one registry line
    registered = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["entry-points"][GROUP]
    for name, member in sensors().items():
        if member.distribution != "quadcosim":
            continue
        assert registered[name] == f"quadcosim.fmus.{name}" and member.folder == ROOT / "fmus" / name
        assert all((member.folder / p.rsplit("/", 1)[1].replace("<Model>", name)).is_file() for p in own), name
    # each check the checklist names is a declared one, read by the test it is named with, and
    # those tests read the registry: no model's name in them
    for check, test in re.findall(r"`([A-Z_]+)`[^`]*?(?:and `[A-Z_]+`[^`]*?)?for `(tests/test_\w+\.py)`", text):
        assert check in CHECKS, check
        source = (ROOT / test).read_text()
        assert f'"{check}"' in source, (check, test)
        assert not [name for name in sensors() if f'"{name}"' in source], test
    assert set(CHECKS) <= set(re.findall(r"`([A-Z_]+)`", text))  # every check is in the checklist


def test_the_estimator_and_model_checklists_name_the_registries_the_dummies_extend():
    """The registry line of each dummy test is the one its checklist names."""
    from quadcosim.calibration.flight import catalogue
    from quadcosim.estimators import kinds

    estimator = _section("Adding an estimator")
    assert Path(kinds.__file__).relative_to(ROOT).as_posix() in _paths(estimator)
    assert "estimators/contract.py" in _paths(estimator) and "`KINDS`" in estimator
    model = _section("Adding a flight-log model or autopilot")
    assert Path(catalogue.__file__).relative_to(ROOT).as_posix() in _paths(model) and "`MODELS`" in model
    from quadcosim.calibration.flight import autopilot

    assert Path(autopilot.__file__).relative_to(ROOT).as_posix() in _paths(model) and "`AUTOPILOTS`" in model
    scenario = _section("Adding a scenario")
    assert "scenarios/catalogue.py" in _paths(scenario) and "`MODULES`" in scenario
