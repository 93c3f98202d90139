"""``--set`` read once: option values and ``Block.parameter`` settings checked against what the scenario
declares (its options, its blocks' declared parameters, the FMUs' variable tables) before anything is
built, and set on the built blocks through the block contract (``parameter_values``, ``set_parameter``)."""

import pytest
from quadcosim.orchestrator import Block, FMUBlock, System
from quadcosim.orchestrator.blocks import Constant

from quadcosim import scenarios
from quadcosim.main import main as cli


def test_every_scenario_declares_the_blocks_it_builds():
    """``extra["blocks"]`` of each scenario this package registers names every block of its default system,
    as what it is: the FMU model, or the block's class (the constants that tie off inputs aside). A third
    party's scenario may declare none: its settings are then checked once its system is built."""
    from quadcosim.scenarios.catalogue import registrations

    ours = [name for name, (_, distribution) in registrations().items() if distribution == "quadcosim"]
    assert {"tp", "gain-study", "ir-calibration"} <= set(ours)
    for name in ours:
        scenario = scenarios.get(name)
        declared = scenario.extra["blocks"]
        system = scenario.system(scenario.parse({}))
        for block_name, block in system.blocks.items():
            if isinstance(block, Constant) and block.ties:
                continue
            assert block_name in declared, f"{name}: block {block_name} is built but not declared"
            if isinstance(block, FMUBlock):
                assert declared[block_name] == block.model, f"{name}: {block_name}"
            else:
                assert isinstance(block, declared[block_name]), f"{name}: {block_name}"


@pytest.fixture
def nothing_built(monkeypatch):
    """tp, its build replaced by one that fails the test: a setting refused here is refused unbuilt."""
    tp = scenarios.get("tp")

    def build(*args, **kwargs):
        raise AssertionError("the system was built before the settings were checked")

    monkeypatch.setattr(tp, "build", build)
    return tp


@pytest.mark.parametrize("setting, error, message", [
    ("IMU.gyro_noise_densty=1e-3", KeyError, "IMU has no parameter 'gyro_noise_densty'. Did you mean "
                                             "gyro_noise_density"),
    ("IMU.gyro_noise_density=1e-3 deg/s/Hz0.5", ValueError, "the unit is rad/s/Hz0.5, not 'deg/s/Hz0.5'"),
    ("IMU.gyro_bias=0.01,0", ValueError, "has 3 components: give 3 values, comma-separated, not 2"),
    ("IMU.seed=3", ValueError, "IMU.seed is set by scenario tp's option seed: use --set seed=..."),
    ("Imu.seed=1", KeyError, "unknown block 'Imu' in 'Imu.seed'. Did you mean IMU?"),
    ("Controller.kp_yw=50", KeyError, "Controller has no parameter 'kp_yw'. Did you mean kp_yaw"),
    ("Controller.kp=-1", ValueError, "controller gain kp = -1.0 must be finite and non-negative"),
    ("Controller.kp=144 1/s", ValueError, "Controller.kp = '144 1/s': the unit is 1/s^2, not '1/s'"),
    ("Controller.ki_xy=5", ValueError, "ki_xy = 5.0 must be below kp_xy * kd_xy"),
    ("kp=1", ValueError, "unknown option 'kp' for scenario tp. Did you mean k"),
    ("duration=soon", ValueError, "option duration='soon' is not a valid float"),
])
def test_a_wrong_setting_is_refused_before_anything_is_built(nothing_built, setting, error, message):
    with pytest.raises(error, match=message.replace("(", r"\(").replace(")", r"\)").replace("*", r"\*")
                       .replace("?", r"\?").replace("^", r"\^").replace(".", r"\.")):
        scenarios.run("tp", [setting])


def test_settings_are_read_once_into_typed_values(nothing_built):
    """Text with its unit, a vector, a Boolean and a gain become the values they stand for, once."""
    options = nothing_built.parse(["IMU.gyro_noise_density=0.002 rad/s/Hz0.5", "IMU.gyro_bias=0.01,0,-0.02",
                                   "MotorMagnetics.regenerative=on", "Controller.kp_yaw=50", "noise=true"])
    assert options["IMU.gyro_noise_density"] == 0.002 and options["IMU.gyro_bias"] == [0.01, 0.0, -0.02]
    assert options["MotorMagnetics.regenerative"] is True and options["Controller.kp_yaw"] == 50.0
    assert options["noise"] is True
    with pytest.raises(ValueError, match="--set 'noise': write key=value"):
        scenarios.run("tp", ["noise"])


def test_a_block_without_declared_parameters_is_set_through_the_contract_once_built():
    """A Python block whose class declares no parameters offers its public numeric attributes; one that
    declares them offers those alone, read and set through its own methods."""

    class Gain(Block):
        inputs, outputs = ("u",), ("y",)

        def __init__(self):
            super().__init__("Gain")
            self.k, self.clip, self.label = 2.0, True, "gain"

    class Held(Block):
        outputs = ("y",)
        parameter_units = {"level": "m"}

        def __init__(self):
            super().__init__("Held")
            self.levels = [0.5]

        def parameter_values(self):
            return {"level": self.levels[-1]}

        def set_parameter(self, name, value):
            self.levels.append(value)

    system = System()
    gain, held = system.add(Gain()), system.add(Held())
    assert gain.parameter_values() == {"clip": True, "k": 2.0}
    assert system.set_parameter("Gain.k", "3") == 3.0 and gain.k == 3.0
    assert system.set_parameter("Held.level", 1.5) == 1.5 and held.levels == [0.5, 1.5]
    with pytest.raises(KeyError, match=r"Held has no parameter 'levels'\. Did you mean level\?"):
        system.set_parameter("Held.levels", 1.0)


def test_a_wrong_setting_from_the_command_line_names_the_fix_and_leaves_no_folder(tmp_path, capsys):
    assert cli(["run", "tp", "--set", "Controller.kp_yw=50", "--out", str(tmp_path / "run")]) == 2
    assert "Did you mean kp_yaw" in capsys.readouterr().err
    assert not (tmp_path / "run").exists()
