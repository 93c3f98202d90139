"""What the scenarios' figures say: titles naming gains and faults, no empty axis, a unit on
every axis, a floor under the span of a still vehicle's axes, fault windows shaded."""

import re

import matplotlib
import numpy as np
import pytest
from quadcosim.orchestrator import Fault, Result

from quadcosim import scenarios

matplotlib.use("Agg")


def drawn(monkeypatch, module_name: str) -> dict:
    """Keep the figures a scenario module saves, by file name, instead of closing them."""
    import importlib

    from quadcosim.scenarios import catalogue

    registered = catalogue.registrations().get(module_name.replace("_", "-"))
    module = importlib.import_module(registered[0] if registered else f"quadcosim.scenarios.{module_name}")
    figures = {}

    def keep(figure, out_dir, name):
        figures[name] = figure
        return name

    monkeypatch.setattr(module, "save_figure", keep)
    return figures


def check_axes(figure):
    """Every axis draws something and states its unit; the bottom one says time (s)."""
    axes = [ax for ax in figure.axes if ax.get_visible()]
    for ax in axes:
        assert ax.lines or ax.collections, f"empty axis {ax.get_ylabel()!r}"
        assert any(len(line.get_xdata()) > 1 for line in ax.lines), ax.get_ylabel()
        assert re.search(r"\(.+\)", ax.get_ylabel()), f"no unit in {ax.get_ylabel()!r}"
    assert axes[-1].get_xlabel() == "time (s)"


def spans(ax) -> list[tuple[float, float]]:
    """Shaded time windows (axvspan) of an axis, (start, stop) in s."""
    return [(round(p.get_x(), 9), round(p.get_x() + p.get_width(), 9)) for p in ax.patches if hasattr(p, "get_width")]


def title_of(options, faults=()):
    tp = scenarios.get("tp")
    meta = {"faults": [scenarios.fault_record(f) for f in faults]}
    from quadcosim.scenarios.tp import figure_title

    return figure_title(Result(np.zeros(1), [], np.zeros((1, 0)), meta), tp.parse(options))


def test_tp_titles_tell_gains_and_faults_apart():
    """The lab's runs with kP = kI = 0.1 and 100 differ in their titles, which name the gains."""
    small = title_of({"estimator": "passive", "kP": 0.1, "kI": 0.1})
    large = title_of({"estimator": "passive", "kP": 100.0, "kI": 100.0})
    assert small != large
    assert "kP = 0.1 1/s" in small and "kI = 100 1/s²" in large
    assert "k = 0.05 1/s" in title_of({})
    faulted = title_of({"feedback": "estimate"}, [Fault("IMU.omega_x", "offset", 2.0, 3.0, 0.1)])
    assert "fault: offset +0.1 on IMU.omega_x, 2-3 s" in faulted
    assert "controller fed by the estimate" in faulted
    assert "wind_n=3.0" in title_of({"wind_n": 3.0})  # an option off its default is stated
    assert "seed" not in title_of({})


def test_tp_figures_show_truth_estimate_error_and_the_fault(monkeypatch, tmp_path):
    figures = drawn(monkeypatch, "tp")
    scenarios.run("tp", {"estimator": "explicit", "kI": 0.3, "bias": True, "duration": 1.0}, tmp_path / "run",
                  faults=[Fault("IMU.omega_x", "offset", 0.4, 0.6, 0.1)])
    assert set(figures) == {"roll_pitch.png", "yaw.png", "bias.png"}
    for figure in figures.values():
        check_axes(figure)
        assert "kI = 0.3 1/s²" in figure.get_suptitle() and "IMU.omega_x" in figure.get_suptitle()
        for ax in figure.axes:
            assert (0.4, 0.6) in spans(ax)
    roll_pitch = figures["roll_pitch.png"].axes
    assert [line.get_label() for line in roll_pitch[0].lines] == ["roll, truth", "roll, estimate"]
    assert roll_pitch[2].get_ylabel() == "estimate - truth (deg)"


def test_a_still_axis_keeps_a_floor_under_its_span(monkeypatch, tmp_path):
    """Hovering without noise, the attitude moves by under 1e-6 deg: the axes still span 1 deg
    (angles) and 0.05 deg (errors), and no bias figure is drawn for the linear filter."""
    figures = drawn(monkeypatch, "tp")
    result, _ = scenarios.run("tp", {"flight": "hover", "duration": 0.5, "bias": True}, tmp_path / "run")
    assert np.degrees(np.ptp(result["Quadrotor.theta1"])) < 1e-3
    assert set(figures) == {"roll_pitch.png", "yaw.png"}  # the linear filter estimates no bias
    roll, pitch, error = figures["roll_pitch.png"].axes
    for ax, floor in ((roll, 1.0), (pitch, 1.0), (error, 0.05)):
        low, high = ax.get_ylim()
        assert high - low >= floor * (1 - 1e-9)
        assert not ax.yaxis.get_major_formatter().get_offset()


@pytest.mark.parametrize("name, options, files", [
    ("open-loop", {"duration": 1.0}, {"open_loop.png", "imu.png"}),
    ("rig", {"reference": 0.2, "sweep": 0.3, "rest": 0.1, "free": 0.3}, {"rig_field.png"}),
])
def test_open_loop_and_rig_figures_name_the_run(monkeypatch, tmp_path, name, options, files):
    figures = drawn(monkeypatch, name.replace("-", "_"))
    scenarios.run(name, options, tmp_path / "run", faults=[Fault("IMU.omega_x", "offset", 0.3, 0.5, 0.1)])
    assert set(figures) == files
    for figure in figures.values():
        check_axes(figure)
        title = figure.get_suptitle()
        assert title.startswith(f"{name}:") and "IMU noise on" in title
        assert "fault: offset +0.1 on IMU.omega_x, 0.3-0.5 s" in title
        assert "seed" not in title.lower() and "cf." not in title


@pytest.mark.parametrize("name", ["tp", "open-loop"])
def test_without_a_folder_no_figure_is_drawn(monkeypatch, name):
    """A run that keeps no file (a sweep member, a Python caller) draws nothing: figures were
    half of a short member's CPU time."""
    import matplotlib.pyplot as plt

    figures = drawn(monkeypatch, name.replace("-", "_"))
    before = plt.get_fignums()
    _, metrics = scenarios.run(name, {"duration": 0.3})
    assert figures == {} and metrics["figures"] == [] and plt.get_fignums() == before


def test_result_plot_labels_the_unit(tmp_path):
    result = Result(np.arange(3.0), ["IMU.acc_x", "IMU.acc_y", "Setpoint.c1", "Probe.y"], np.ones((3, 4)),
                    {"units": {"IMU.acc_x": "m/s2", "IMU.acc_y": "m/s2", "Setpoint.c1": "1", "Probe.y": ""}})
    assert result.plot("IMU.acc").get_ylabel() == "IMU.acc (m/s2)"
    assert result.plot("Setpoint.c").get_ylabel() == "Setpoint.c (1)"
    assert result.plot("Probe.y").get_ylabel() == "Probe.y (unit unknown)"
    assert result.plot("IMU.acc_x", "Setpoint.c1").get_ylabel() == "IMU.acc_x (m/s2), Setpoint.c1 (1)"
    assert result.plot("IMU.acc", scale=100.0, unit="cm/s2").get_ylabel() == "IMU.acc (cm/s2)"
    with pytest.raises(ValueError, match="give the unit of the scaled values"):
        result.plot("IMU.acc", scale=100.0)


LOOP = ["Setpoint", "Controller", "MotorMagnetics", "Quadrotor", "IMU", "Quaternion_estim"]


@pytest.mark.parametrize("feedback", ["gt", "estimate"])
def test_tp_diagram_reads_as_the_labs_loop(feedback):
    """Blocks in the order of the lab's diagram; feedbacks below the row; every box, arrow and
    label inside the canvas; no two labels overlap; the title clear of the drawing; each
    label just above its arrow's run."""
    from quadcosim.orchestrator import diagram

    tp = scenarios.get("tp")
    options = tp.parse({"feedback": feedback})
    system = tp.build(options)
    order, links, _ = diagram._wiring(system)
    assert order == LOOP
    column = {n: i for i, n in enumerate(order)}
    arrows = diagram._route(order, links, column, diagram._box_height(links, column))
    back = {(a.source, a.destination) for a in arrows if a.side < 0}
    fed_back = "Quaternion_estim" if feedback == "estimate" else "Quadrotor"
    assert {("MotorMagnetics", "Controller"), (fed_back, "Controller")} <= back
    system.inject(Fault("IMU.omega_x", "offset", 1.0, 2.0, 0.2))
    figure = diagram.figure(system, tp.title(options))
    ax = figure.axes[0]
    assert ax.title.get_text().endswith("offset fault on the input IMU.omega_x, 1-2 s")
    renderer = figure.canvas.get_renderer()
    canvas = ax.get_window_extent(renderer)
    texts = [t for t in ax.texts if t.get_text()]
    parts = [*texts, *ax.patches, *ax.lines]
    for part in parts:
        box = part.get_window_extent(renderer)
        assert canvas.x0 - 1 <= box.x0 and box.x1 <= canvas.x1 + 1, part
        assert canvas.y0 - 1 <= box.y0 and box.y1 <= canvas.y1 + 1, part
    title = ax.title.get_window_extent(renderer)
    assert title.y0 >= canvas.y1 and "controller fed by the" in ax.title.get_text()
    boxes = [t.get_window_extent(renderer) for t in texts]
    for i, a in enumerate(boxes):
        for b in boxes[i + 1:]:
            assert not a.overlaps(b), (texts[boxes.index(a)].get_text(), texts[boxes.index(b)].get_text())
    runs = [line for line in ax.lines if len(line.get_ydata()) == 3]  # out, along the lane, in
    for arrow in (a for a in arrows if a.side):
        label = next(t for t in texts if t.get_text() == arrow.label)
        run = next(line for line in runs if line.get_ydata()[1] == pytest.approx(arrow.level)
                   and min(line.get_xdata()) <= label.get_position()[0] <= max(line.get_xdata()))
        assert 0 < label.get_position()[1] - run.get_ydata()[1] < 0.1  # just above its own run
    import matplotlib.pyplot as plt

    plt.close(figure)


def test_fold_names_vectors_and_renamed_components():
    from quadcosim.orchestrator.diagram import fold

    assert fold(["acc_x", "acc_y", "acc_z", "hold"]) == "acc[xyz], hold"
    assert fold([f"omega_r{n}" for n in range(1, 5)]) == "omega_r[1-4]"
    assert fold([f"q_est{n}→q{n}" for n in range(4)]) == "q_est[0-3]→q[0-3]"
    assert fold(["u_batt"]) == "u_batt"


def test_sweep_plot_axes_carry_units(tmp_path):
    """The metric's unit from the end of its name, the option's from its help; the title names
    the sweep and what it held fixed (from sweep.json)."""
    import json

    from quadcosim.studies.sweep import figure
    from quadcosim.studies.sweep.command import _plot_context

    assert figure.metric_unit("rms_error_deg[0]") == "deg" and figure.metric_unit("bias_convergence_s") == "s"
    assert figure.metric_unit("real_time_factor") == ""
    (tmp_path / "sweep.json").write_text(json.dumps({"scenario": "tp", "name": None, "varied": ["k"],
                                                     "description": {"set": ["duration=3"]}, "members": []}))
    units, subtitle, _ = _plot_context(tmp_path)
    assert units["k"] == "1/s" and units["duration"] == "s" and subtitle == "tp sweep; duration=3"
    columns = {"status": ["ok"] * 3, "k": [0.05, 0.2, 1.0], "rms_error_deg[0]": [0.04, 0.01, 0.1]}
    ax = figure.plot(columns, "rms_error_deg[0]", "k", units=units, subtitle=subtitle).axes[0]
    assert ax.get_xlabel() == "k (1/s)" and ax.get_ylabel() == "rms_error_deg[0] (deg)"
    assert ax.get_title().endswith("tp sweep; duration=3")


@pytest.mark.parametrize("name, options", [("tp", {"accelerometer": "gravity"}), ("rig", {}), ("open-loop", {}),
                                           ("static-cal", {}), ("ir-calibration", {})])
def test_every_python_block_states_the_unit_of_each_output(name, options):
    """The Python blocks of the scenarios (setpoint tables, controller, estimator, ablations)
    give a unit to every output, as the FMUs' variable tables do: plots and result files
    label them."""
    from quadcosim.orchestrator import Constant, FMUBlock

    scenario = scenarios.get(name)
    system = scenario.build(scenario.parse(options))
    for block in system.blocks.values():
        if isinstance(block, (FMUBlock, Constant)) or block.name in ("Kalman", "Regression", "Rls", "Faults"):
            continue
        assert set(getattr(block, "units", {})) == set(block.outputs), block.name
        assert all(block.units[output] for output in block.outputs), block.name


def test_result_plot_of_a_real_run_labels_the_units_of_the_variable_tables():
    result, _ = scenarios.run("open-loop", {"duration": 0.05})
    assert result.plot("IMU.acc").get_ylabel() == "IMU.acc (m/s2)"
    assert result.plot("MotorMagnetics.omega_r1").get_ylabel() == "MotorMagnetics.omega_r1 (rad/s)"
