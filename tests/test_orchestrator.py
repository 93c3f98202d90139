"""The co-simulation master: wiring, multi-rate, faults, recording, exports and failures."""

import gc
import tracemalloc

import numpy as np
import pytest
import scipy.io
from quadcosim.orchestrator import AlgebraicLoopError, Block, Fault, FMUBlock, Result, System, Table

from quadcosim import scenarios


class Ramp(Block):
    """y = t: a known signal."""

    outputs = ("y",)
    feedthrough = False

    def step(self, t, u, y):
        y[0] = t


class Probe(Block):
    """Copies its input to its output, and counts its steps."""

    inputs = ("u",)
    outputs = ("y",)

    def start(self, t0, dt):
        self.times = []

    def step(self, t, u, y):
        self.times.append(t)
        y[0] = u[0]


class Gain(Block):
    inputs = ("u",)
    outputs = ("y",)

    def step(self, t, u, y):
        y[0] = 2.0 * u[0]


def probe_system(dt=1e-3, period=1):
    system = System(dt)
    system.add(Ramp("Source"))
    probe = system.add(Probe("Probe", period=period))
    system.connect("Source.y", "Probe.u")
    return system, probe


# ---------------------------------------------------------------- faults
@pytest.mark.parametrize("kind, value, expected", [
    ("offset", 0.5, lambda t: t + 0.5),
    ("scale", -2.0, lambda t: -2.0 * t),
    ("stuck", None, lambda t: np.full_like(t, 0.3)),  # the value at the fault's start
    ("stuck", 7.0, lambda t: np.full_like(t, 7.0)),
    ("dropout", None, lambda t: np.zeros_like(t)),
])
def test_each_fault_acts_inside_its_window_only(kind, value, expected):
    system, _ = probe_system()
    system.inject(Fault("Probe.u", kind, 0.3, 0.6, value))
    result = system.run(1.0)
    t, y = result.time, result["Probe.y"]
    inside = (t >= 0.3 - 1e-12) & (t < 0.6 - 1e-12)
    assert np.allclose(y[inside], expected(t[inside]), atol=1e-12)
    assert np.allclose(y[~inside], t[~inside], atol=1e-12)


def test_noise_fault_statistics_and_window():
    system, _ = probe_system()
    system.inject(Fault("Probe.u", "noise", 1.0, 3.0, 0.2, seed=3))
    result = system.run(4.0)
    t, y = result.time, result["Probe.y"]
    inside = (t >= 1.0 - 1e-12) & (t < 3.0 - 1e-12)
    deviation = y[inside] - t[inside]
    assert abs(deviation.std() / 0.2 - 1) < 0.05 and abs(deviation.mean()) < 0.02
    assert np.array_equal(y[~inside], t[~inside])


def test_fault_on_an_fmu_input():
    system = System()
    system.add(Table("Setpoint", ["c1", "c2", "c3", "c4"], np.full((1, 4), 0.5)))
    system.add(FMUBlock("MotorMagnetics"))
    system.connect("Setpoint.c", "MotorMagnetics.c")
    system.inject(Fault("MotorMagnetics.c2", "dropout", 0.0, 10.0))
    result = system.run(0.3)
    assert result["MotorMagnetics.omega_r2"][-1] == 0.0 and result["MotorMagnetics.omega_r1"][-1] > 300


# ---------------------------------------------------------------- multi-rate and order
@pytest.mark.parametrize("period", [1, 2, 5])
def test_block_at_one_kth_rate_steps_every_kth_macro_step(period):
    system, probe = probe_system(period=period)
    result = system.run(0.1)
    steps = np.round(np.array(probe.times) / 1e-3).astype(int)
    assert np.array_equal(steps, np.arange(0, 101, period))
    # between its steps the output holds
    y = result["Probe.y"]
    assert np.allclose(y, (np.arange(101) // period) * period * 1e-3)


def test_fmu_at_a_multiple_of_the_macro_step():
    system = System()
    system.add(Table("Setpoint", ["c1", "c2", "c3", "c4"], np.full((1, 4), 0.5)))
    system.add(FMUBlock("MotorMagnetics", period=4))
    system.connect("Setpoint.c", "MotorMagnetics.c")
    w = system.run(0.2)["MotorMagnetics.omega_r1"]
    changes = np.flatnonzero(np.diff(w)) + 1
    assert np.all(changes % 4 == 0) and len(changes) == 50


def test_algebraic_loop_is_reported_with_its_blocks():
    system = System()
    system.add(Gain("A"))
    system.add(Gain("B"))
    system.connect("A.y", "B.u")
    system.connect("B.y", "A.u")
    with pytest.raises(AlgebraicLoopError) as error:
        system.run(0.01)
    assert "A -> B -> A" in str(error.value) or "B -> A -> B" in str(error.value)


def test_loop_through_a_block_without_feedthrough_is_not_algebraic():
    system = System()
    system.add(Table("Setpoint", ["c1", "c2", "c3", "c4"], np.full((1, 4), 0.4)))
    system.add(FMUBlock("MotorMagnetics"))
    system.add(Probe("Probe"))
    system.connect("Setpoint.c", "MotorMagnetics.c")
    system.connect("MotorMagnetics.omega_r1", "Probe.u")
    assert [b.name for b in system.order()] == ["Setpoint", "MotorMagnetics", "Probe"]


# ---------------------------------------------------------------- hot path
def test_no_allocation_grows_with_the_number_of_steps():
    def peak(seconds):
        scenario = scenarios.get("open-loop")
        system = scenario.build(scenario.parse({"duration": seconds}))
        gc.collect()
        tracemalloc.start()
        result = system.run(seconds)
        _, top = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        return top - result.data.nbytes - result.time.nbytes  # all but the record, held once

    peak(0.5)  # the first run in a process pays for its caches
    short, long = peak(0.5), peak(2.5)
    print(f"open-loop: {short / 1e3:.0f} kB beside the record at 0.5 s, {long / 1e3:.0f} kB at 2.5 s")
    assert long - short < 64 * 1024  # 2000 more steps (measured -16 kB): a leak of 41 bytes a step fails


# ---------------------------------------------------------------- results
def test_exports_load_back_equal(tmp_path):
    _, metrics = scenarios.run("open-loop", {"duration": 0.2})
    result, _ = scenarios.run("open-loop", {"duration": 0.2})
    result.save(tmp_path, formats=("npz", "mat", "csv"))
    back = Result.from_npz(tmp_path / "results.npz")
    assert back.names == result.names and np.array_equal(back.data, result.data)
    assert np.array_equal(back.time, result.time)
    mat = scipy.io.loadmat(tmp_path / "results.mat", squeeze_me=True)
    assert np.array_equal(mat["time"], result.time)
    assert np.array_equal(mat["IMU"]["acc_x"].item(), result["IMU.acc_x"])
    csv = np.genfromtxt(tmp_path / "results.csv", delimiter=",", names=True)
    assert np.array_equal(csv["IMUacc_x"], result["IMU.acc_x"])  # numpy drops the dot in names
    assert np.array_equal(csv["time"], result.time)


def test_same_scenario_and_seed_give_identical_results():
    a, _ = scenarios.run("open-loop", {"duration": 0.3, "seed": 4})
    b, _ = scenarios.run("open-loop", {"duration": 0.3, "seed": 4})
    c, _ = scenarios.run("open-loop", {"duration": 0.3, "seed": 5})
    assert np.array_equal(a.data, b.data)
    assert not np.array_equal(a["IMU.gyro"], c["IMU.gyro"])


def test_vector_signals_connect_and_index():
    result, _ = scenarios.run("open-loop", {"duration": 0.05})
    assert result["IMU.acc"].shape == (51, 3)
    assert result["MotorMagnetics.omega_r"].shape == (51, 4)
    assert result["IMU.R_reel"].shape == (51, 9)


# ---------------------------------------------------------------- declaration rules
def test_set_input_refuses_a_connected_input_as_connect_does():
    system, _ = probe_system()
    with pytest.raises(ValueError, match="Probe.u is already connected to Source.y"):
        system.set_input("Probe.u", 1.0)
    with pytest.raises(ValueError, match="Probe.u is already connected to Source.y"):
        system.connect("Source.y", "Probe.u")
    free = System()
    free.add(Probe("Probe"))
    free.set_input("Probe.u", 2.5)
    with pytest.raises(ValueError, match="already connected to Const_Probe_u.u"):
        free.connect("Const_Probe_u.u", "Probe.u")
    assert free.run(0.002)["Probe.y"].tolist() == [2.5, 2.5, 2.5]


def test_a_wiring_drawn_before_is_copied_from_the_diagram_cache(tmp_path, monkeypatch):
    from quadcosim.orchestrator import diagram

    def system(gain):
        s = System()
        s.add(Ramp("Source"))
        s.add(Probe("Probe"))
        if gain:
            s.set_input("Probe.u", gain)  # a tie in the place of the arrow
        else:
            s.connect("Source.y", "Probe.u")
        return s

    cache = tmp_path / "cache"
    first = diagram.draw(system(0), tmp_path / "a" / "diagram.png", "t", cache=cache)
    assert [p.name for p in cache.iterdir()] == [diagram.wiring_key(system(0), "t") + ".png"]
    monkeypatch.setattr(diagram, "figure", lambda *a: pytest.fail("drawn again"))
    second = diagram.draw(system(0), tmp_path / "b" / "diagram.png", "t", cache=cache)
    assert second.read_bytes() == first.read_bytes()
    keys = {diagram.wiring_key(system(0), "t"), diagram.wiring_key(system(0), "other title"),
            diagram.wiring_key(system(2.5), "t")}
    assert len(keys) == 3  # another title or another wiring: another picture
    monkeypatch.undo()
    blocked = tmp_path / "a file"  # a cache that cannot be written: drawn all the same
    blocked.write_text("")
    assert diagram.draw(system(2.5), tmp_path / "c.png", "t", cache=blocked / "diagrams").is_file()


def test_diagram_draws_a_tied_input_with_its_value_and_no_block(tmp_path):
    from quadcosim.orchestrator.diagram import _wiring

    system = System()
    system.add(Probe("Probe"))
    system.set_input("Probe.u", 2.5)
    system.add(Ramp("Source"))
    order, links, constants = _wiring(system)
    assert order == ["Probe", "Source"]  # the tie is no block of the picture
    assert constants == {"Probe": {2.5: ["u"]}}
    assert not links
