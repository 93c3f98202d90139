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

import pytest

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
    assert "registered by dummy-members" in message and "fix the line or the member" in message
    assert "not a quadcosim.estimators.kinds.Kind named 'gyro-only'" in message


def test_a_dummy_calibration_model_is_one_file_and_one_line(tmp_path):
    from tests.flightlog_synthetic import write_log

    log = tmp_path / "flight.bin"
    write_log(log, duration=40.0)
    found = _with_member("quadcosim.interference", "nothing = dummy_model:NOTHING", '''
        code, _ = cli("calibrate", "flight.bin", "--out", "out")
        metrics = json.load(open("out/metrics.json"))
        found["default"] = [code, sorted(metrics["models"])]
        code, _ = cli("calibrate", "flight.bin", "--models", "nothing", "current", "--out", "chosen")
        metrics = json.load(open("chosen/metrics.json"))
        found["chosen"] = [code, sorted(metrics["models"]), metrics["models"]["nothing"]["explained_test"]]
        from quadcosim.calibration.flight import catalogue
        found["names"] = list(catalogue.models())
        found["orders"] = [list(catalogue.preferred("in_file")), list(catalogue.preferred("autopilot"))]
        from quadcosim.scenarios.registries import model_rows
        found["documented"] = [row[0] for row in model_rows()]
    ''', tmp_path)
    assert found["default"][0] == 0 and "nothing" in found["default"][1]  # --models' default: every model
    assert found["chosen"][:2] == [0, ["current", "nothing"]] and abs(found["chosen"][2]) < 1e-9
    assert found["names"] == ["current", "throttle", "motors", "metge", "dynamic", "nothing"]  # fitted after ours
    assert "nothing" not in found["orders"][0] + found["orders"][1]  # neither the file nor an autopilot carries it
    assert found["documented"][-2:] == ["`dynamic`", "`nothing`"]  # the docs' table, by its rank


def test_a_dummy_autopilot_is_one_file_and_one_line(tmp_path):
    """The dummy's own log (tests/registry_dummies/dummy_autopilot.py: its text format, the same
    synthetic flight as an ArduPilot log) is detected, read, shown by ``log info`` and calibrated,
    the export written as the dummy's own parameter file under its own firmware's arithmetic."""
    from tests.flightlog_synthetic import write_log

    write_log(tmp_path / "flight.log", duration=40.0, gps=True)
    found = _with_member("quadcosim.autopilots", "Dummy = dummy_autopilot:AUTOPILOT", '''
        from quadcosim.flightlogs import LogError, detect_format, read_log
        import dummy_autopilot
        source = read_log("flight.log")
        dummy_autopilot.write_log(source, "flight.dummy")
        dummy_autopilot.write_log(source, "nobattery.dummy", parts=("mag", "imu", "att", "mot"))
        found["format"] = detect_format("flight.dummy")
        log = read_log("flight.dummy")
        found["read"] = [log.autopilot, log.format, len(log.compasses[0].time), len(source.compasses[0].time)]
        try:
            read_log("nobattery.dummy").require("a test", "battery")
        except LogError as error:
            found["missing"] = str(error)
        open("notes.txt", "w").write("not a log\\n")
        try:
            read_log("notes.txt")
        except LogError as error:
            found["unknown"] = str(error)
        code, shown = cli("log", "info", "flight.dummy")
        found["info"] = [code, shown.splitlines()[0]]
        code, _ = cli("calibrate", "flight.dummy", "--models", "current", "--out", "out")
        metrics = json.load(open("out/metrics.json"))
        found["calibrated"] = [code, metrics["files"], metrics["export"]["file"], metrics["export"]["firmware"]]
        found["written"] = open("out/dummy.cfg").read().splitlines()
        found["export"] = metrics["export"]
        code, _ = cli("calibrate", "flight.dummy", "--score", "out/dummy.cfg", "--out", "scored")
        found["scored"] = [code, json.load(open("scored/metrics.json"))["score"]]
        from quadcosim.scenarios.registries import autopilot_rows
        found["documented"] = [list(row) for row in autopilot_rows() if row[0] == "Dummy"]
    ''', tmp_path)
    assert found["format"] == "dummy-text"  # its detection claims its own log
    assert found["read"][:2] == ["Dummy", "dummy-text"] and found["read"][2] == found["read"][3] > 100
    # a missing part is named in the dummy's own words, not ArduPilot's
    assert "the battery (bat records). Log them (DUMMY_LOG_RECORDS)" in found["missing"]
    assert "unknown log format" in found["unknown"] and "dummy autopilot text (.dummy)" in found["unknown"]
    assert found["info"] == [0, "flight.dummy: dummy-text, Dummy Dummy 1.0"]
    assert found["calibrated"][0] == 0 and "dummy.cfg" in found["calibrated"][1]
    assert found["calibrated"][2:] == ["dummy.cfg", "Dummy 1.0"]
    written = dict(line.split(" = ") for line in found["written"])
    assert set(written) == {"DUMMY_OFS_X", "DUMMY_OFS_Y", "DUMMY_OFS_Z", "DUMMY_MOT_X", "DUMMY_MOT_Y", "DUMMY_MOT_Z",
                            "DUMMY_MOT_ON"}
    export = found["export"]
    # the flight's current field (0.3, -0.5, 0.8 uT/A, tests/flightlog_synthetic.py) exported by the dummy's
    # firmware, and scored under it: the heading error drops from the log's values
    assert export["model"] == "current" and written["DUMMY_MOT_ON"] == "1", export["notes"]
    assert [float(written[f"DUMMY_MOT_{a}"]) for a in "XYZ"] == pytest.approx([0.3, -0.5, 0.8], abs=0.05)
    # and the hard iron of the synthetic flight (10, -20, 5 uT); measured 0.58 deg against 27.0 deg as flown
    assert [float(written[f"DUMMY_OFS_{a}"]) for a in "XYZ"] == pytest.approx([10.0, -20.0, 5.0], abs=1.0)
    assert export["heading_rms_deg"] < 1.0 < 20.0 < export["as_flown"]["heading_rms_deg"], export
    # the file written, read back by --score as the dummy's own lines, scores as the export did
    assert found["scored"][0] == 0 and found["scored"][1]["parameters"] == 7
    assert found["scored"][1]["heading_rms_deg"] == pytest.approx(export["heading_rms_deg"], abs=1e-3)
    assert found["documented"] == [["Dummy", "`dummy-text` (dummy autopilot text (.dummy))", "`dummy.cfg`", "",
                                    "`dummy_autopilot`"]]


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
    assert Path(catalogue.__file__).relative_to(ROOT).as_posix() in _paths(model)
    assert "`quadcosim.interference`" in model and "`quadcosim.autopilots`" in model
    assert "tests/registry_dummies/dummy_model.py" in _paths(model)
    assert "tests/registry_dummies/dummy_autopilot.py" in _paths(model)
    from quadcosim.flightlogs import autopilots

    assert Path(autopilots.__file__).relative_to(ROOT).as_posix() in _paths(model)
    scenario = _section("Adding a scenario")
    assert "scenarios/catalogue.py" in _paths(scenario) and '"quadcosim.scenarios"' in scenario
    assert "pyproject.toml" in scenario


def test_the_autopilot_and_model_checklists_are_how_the_package_registers_its_own():
    """Each step of the checklists, as the package's own members take it: every autopilot a folder of
    ``flightlogs/autopilots/`` named in the checklist, registered by one line in ``quadcosim.autopilots``
    that names its ``AUTOPILOT`` under the name its logs give; every interference model a ``Model``
    registered by one line in ``quadcosim.interference``, in one of the files the checklist names; and
    no consumer naming a member's module: the command line, the calibration and the export read the
    registries."""
    import tomllib

    from quadcosim.calibration.flight.catalogue import Model
    from quadcosim.flightlogs.autopilots import Autopilot

    from quadcosim.infra.members import load

    section = _section("Adding a flight-log model or autopilot")
    points = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["entry-points"]
    autopilots = points["quadcosim.autopilots"]
    assert set(autopilots) >= {"ArduPilot", "PX4"}
    for name, value in autopilots.items():
        module, _, attribute = value.partition(":")
        folder = module.removeprefix("quadcosim.").replace(".", "/")
        assert attribute == "AUTOPILOT" and (ROOT / folder / "__init__.py").is_file(), value
        assert f"`{folder}/`" in section, folder  # the checklist shows each folder as the example
        member = load(value)
        assert isinstance(member, Autopilot) and member.name == name and member.formats
    # the models an autopilot can carry (Model.autopilot) are those the autopilots' firmware has, on a
    # compass of each (a 4.5 firmware's first compass: ArduPilot's per-motor compensation included)
    from types import SimpleNamespace

    from quadcosim.calibration.flight.catalogue import preferred
    from quadcosim.flightlogs.autopilots import registry

    part = SimpleNamespace(log=SimpleNamespace(firmware="ArduCopter V4.5.0", compasses=[SimpleNamespace(slot=0)]),
                           compass=0)
    carried = {name: set(member.motor_models(part, None)) for name, member in registry().items()}
    assert set().union(*carried.values()) == set(preferred("autopilot")), carried
    models = points["quadcosim.interference"]
    assert set(models) >= {"current", "throttle", "motors", "metge", "dynamic"}
    for name, value in models.items():
        module = value.partition(":")[0].removeprefix("quadcosim.").replace(".", "/") + ".py"
        assert module in _paths(section), module
        member = load(value)
        assert isinstance(member, Model) and member.name == name
    consumers = ["calibration/flight/export.py", "calibration/flight/data.py", "calibration/flight/calibrate.py",
                 "calibration/flight/autopilot.py", "scenarios/flightlog/calibrate.py", "flightlogs/__init__.py",
                 "flightlogs/model.py", "flightlogs/info.py", "scenarios/registries.py"]
    members = ("autopilots.ardupilot", "autopilots.px4", '"ArduPilot"', '"PX4"', "LinearModel", "MetgeModel",
               "DynamicModel")
    named = {path: [m for m in members if m in (ROOT / path).read_text()] for path in consumers}
    assert {path: found for path, found in named.items() if found} == {}
