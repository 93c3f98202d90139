"""The benchmark's C reference loops (``benchmarks/c/loops.c``) make the same FMI calls and the
same explicit filter and controller as the orchestrator: their trajectories are equal to the
last bit, which is what lets ``quadcosim bench`` compare their speeds."""

import pytest
from quadcosim.benchmarks import master


@pytest.mark.parametrize("scenario, settings", [("open-loop", {}), ("tp", master.CLOSED_LOOP),
                                                ("tp", {"estimator": "explicit", "flight": "tilt", "kI": 0.05})])
def test_the_c_reference_loops_give_the_orchestrators_trajectories(scenario, settings):
    figures = master.compare(scenario, settings, seconds=0.5, repeats=1)
    assert figures["identical"]
    assert figures["us_per_step"] > 0 and figures["c_us_per_step"] > 0


def test_the_c_reference_refuses_a_filter_it_does_not_implement():
    from quadcosim import scenarios

    definition = scenarios.get("tp")
    system = definition.build(definition.parse({"estimator": "explicit", "corrections": "on"}))
    with pytest.raises(ValueError, match="explicit filter without corrections"):
        master.ReferenceLoop(system, 0.1)


def test_bench_draws_its_figures_and_refuses_a_figure_it_cannot_write(tmp_path, capsys, monkeypatch):
    """``quadcosim bench --out``: µs per step, orchestrator beside C, with their ratio, and the
    batch path's rates; a path refused, or another suite, before any timing."""
    import matplotlib.text

    from quadcosim.main import main

    figures = {"open_loop_us_per_step": 1.6, "open_loop_c_us_per_step": 1.5, "closed_loop_us_per_step": 2.2,
               "closed_loop_c_us_per_step": 2.0, "fmu_steps_us": 1.04, "equations_steps_us": 0.97,
               "batch_updates_per_s": 7.0e6, "batch_c_updates_per_s": 7.4e6, "parallel_batch_updates_per_s": 6.6e6}
    kept = []
    monkeypatch.setattr("quadcosim.infra.files.save_figure", lambda fig, path, **o: kept.append(fig) or path)
    master.draw(figures, tmp_path / "bench.png")
    steps, batch = kept[0].axes
    heights = [bar.get_height() for bar in steps.patches]
    assert heights == [1.6, 2.2, 1.04, 1.5, 2.0, 0.97]
    ratios = [t.get_text() for t in steps.get_children() if isinstance(t, matplotlib.text.Annotation)]
    assert ratios == ["x 1.07", "x 1.10", "x 1.07"]
    assert [bar.get_height() for bar in batch.patches] == pytest.approx([7.0, 7.4, 6.6])
    monkeypatch.setattr(master, "measure", lambda *a: pytest.fail("timed before the path was checked"))
    assert main(["bench", "--out", str(tmp_path / "bench.xyz")]) == 2
    assert "bench.xyz" in capsys.readouterr().err
    assert main(["bench", "infrared", "--out", str(tmp_path / "b.png")]) == 2
    assert "master suite's figures only" in capsys.readouterr().err
