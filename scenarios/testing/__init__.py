"""A pytest plugin for testing estimators and controllers on the lab's scenarios, on short horizons.

Installed with the package (entry point ``pytest11``), so that its fixtures are there in any
test without an import:

``run_scenario(name, duration=..., **options)``
    Runs a scenario (:func:`quadcosim.scenarios.run`) for a short horizon, without result files, figures
    or wiring diagram (unless ``out`` is given), and returns its :class:`quadcosim.orchestrator.Result`
    with the scenario's metrics as ``result.metrics``.
``make_system(dt=...)``
    An empty :class:`quadcosim.orchestrator.System`, to wire blocks of one's own.
``quadcosim_seed``
    The test's seed: fixed by the test's node id, the same on every run and every worker,
    printed in the report of a failing test. ``run_scenario`` gives it to a scenario's
    ``seed`` option unless the test sets it.

FMU instances are pooled for the session (one pool per process, so one per pytest-xdist
worker) and reset between runs (:mod:`quadcosim.orchestrator.pool`): the second test does not pay for
instantiating the plant. An FMU of one's own is pooled only when its reset is verified (one
step after a reset equals one step of a fresh instance); otherwise each test takes a fresh
instance, which a warning says once: results never depend on the order of the tests. The
checks on a result are in :mod:`quadcosim.scenarios.testing.assertions`.
"""

from __future__ import annotations

import zlib

import pytest
from quadcosim.scenarios.testing.assertions import (
    assert_attitude_error,
    assert_bias_converges,
    assert_bounds,
    assert_runs_close,
    assert_step,
    assert_tracking,
    step_response,
)

#: Seeds are drawn in [1, SEED_LIMIT]: positive 32-bit integers, as the FMUs' ``seed`` takes them.
SEED_LIMIT = 2**31 - 1

_RUNS = pytest.StashKey[list]()
_SEED = pytest.StashKey[int]()


def seed_of(nodeid: str) -> int:
    """The seed of a test: a CRC-32 of its node id, in [1, :data:`SEED_LIMIT`].

    Parameters
    ----------
    nodeid : str
        pytest's node id, ``"tests/test_mine.py::test_hover[0.5]"``.

    Returns
    -------
    int
        The same for the same node id in every session, process and worker.
    """
    return zlib.crc32(nodeid.encode()) % SEED_LIMIT + 1


def pytest_configure(config):
    """Register the marker ``slow`` (a long simulated horizon), so that ``-m "not slow"`` and
    ``--strict-markers`` know it.

    Parameters
    ----------
    config : pytest.Config
    """
    config.addinivalue_line("markers", "slow: a long simulated horizon; deselect with -m 'not slow'")


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """Add a ``quadcosim`` section to a failing test's report: its seed and every run it made.

    Parameters
    ----------
    item : pytest.Item
        The test.
    call : pytest.CallInfo
        The phase (set-up, call, tear-down) just run.
    """
    outcome = yield
    report = outcome.get_result()
    if report.failed and _SEED in item.stash:
        lines = [f"test seed {item.stash[_SEED]}, from the node id {item.nodeid} (the same on a rerun), given to "
                 "every run that sets no seed of its own"]
        lines += [f"run: {text}" for text in item.stash.get(_RUNS, [])]
        report.sections.append(("quadcosim", "\n".join(lines)))


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item):
    """End the session on an interrupted run, as pytest's own KeyboardInterrupt does (exit 2).

    A run stopped by Ctrl-C or SIGTERM raises :class:`quadcosim.orchestrator.RunInterrupted`, an error
    of the simulation: left as it is, pytest would count the test as failed and run the next
    one. It is raised again as a KeyboardInterrupt, naming what the run kept.

    Parameters
    ----------
    item : pytest.Item
        The test.
    """
    from quadcosim.orchestrator.errors import RunInterrupted

    try:
        return (yield)
    except RunInterrupted as error:
        raise KeyboardInterrupt(f"{item.nodeid}: {error}") from error


@pytest.fixture
def quadcosim_seed(request) -> int:
    """The test's seed (:func:`seed_of` its node id), printed if the test fails."""
    seed = seed_of(request.node.nodeid)
    request.node.stash[_SEED] = seed
    return seed


@pytest.fixture(scope="session")
def _quadcosim_pool():
    """The session's FMU instances: kept idle between the plugin's tests, freed at the end."""
    from quadcosim.orchestrator import pool

    yield pool
    pool.reuse(False)


@pytest.fixture
def run_scenario(request, quadcosim_seed, _quadcosim_pool):
    """A function running a scenario for a short horizon and returning its result.

    ``run_scenario(name, duration=None, *, estimator=None, blocks=None, parameters=None,
    faults=(), record=None, out=None, **options)``:

    - ``name``: a scenario (``quadcosim list``), ``"tp"`` for the lab's closed loop;
    - ``duration``: simulated time (s), the scenario's option ``duration``;
    - ``options``: the scenario's options (``estimator="passive"``, ``bias=True``); an
      estimator of one's own as ``estimator="my_filter.py:MyFilter"`` or ``estimator=MyFilter``
      (a class or an instance, :mod:`quadcosim.estimators.contract`); ``seed`` defaults to the test's;
    - ``blocks``: blocks of one's own in the place of the scenario's, ``{"Controller": block}``;
    - ``parameters``: block parameters, ``{"Controller.kp": 100.0, "IMU.gyro_noise_density": 1e-3}``;
    - ``faults``: :class:`quadcosim.orchestrator.Fault` injected; ``record``: signals kept (default: the
      scenario's);
    - ``out``: a folder: results, metrics and figures written there, as ``quadcosim run`` does.

    Returns the :class:`quadcosim.orchestrator.Result`, its metrics in ``result.metrics`` and the test's
    seed and node id in ``result.meta["test"]``.
    """
    from quadcosim import scenarios

    runs = request.node.stash.setdefault(_RUNS, [])
    previous = _quadcosim_pool.reuse(True)

    def run(name, duration=None, *, estimator=None, blocks=None, parameters=None, faults=(), record=None, out=None,
            **options):
        if name not in scenarios.names():
            from quadcosim.orchestrator.fmu import nearest

            raise ValueError(f"run_scenario: no scenario {name!r}.{nearest(str(name), scenarios.names())} "
                             f"Scenarios: {', '.join(scenarios.names())}")
        if duration is not None:
            if isinstance(duration, bool) or not isinstance(duration, (int, float)) or not 0 < duration < float("inf"):
                raise ValueError(f"run_scenario: duration={duration!r} must be a positive number of seconds")
            options["duration"] = duration
        if isinstance(record, str):  # one signal named alone, not its characters
            record = [record]
        if "seed" in scenarios.get(name).options:
            options.setdefault("seed", quadcosim_seed)
        if not isinstance(estimator, (str, type(None))):
            given = estimator
        else:
            given = None
            if estimator is not None:
                options["estimator"] = estimator
        settings = options | dict(parameters or {})
        runs.append(f"{name} " + " ".join(f"{k}={v}" for k, v in settings.items())
                    + (f" estimator={getattr(given, '__name__', type(given).__name__)}" if given is not None else "")
                    + (f" blocks={','.join(blocks)}" if blocks else ""))
        result, metrics = scenarios.run(name, settings, out_dir=out, faults=faults, record=record, estimator=given,
                                        blocks=blocks)
        result.metrics = metrics
        result.meta["test"] = {"seed": options.get("seed", quadcosim_seed), "node": request.node.nodeid}
        return result

    yield run
    _quadcosim_pool.reuse(previous, free=False)  # other tests run as they would without the plugin


@pytest.fixture
def make_system():
    """A function making an empty :class:`quadcosim.orchestrator.System`: ``make_system(dt=1e-3)``, the
    macro step ``dt`` in seconds."""
    from quadcosim.orchestrator import System

    def make(dt: float = 1e-3):
        return System(dt=dt)

    return make


__all__ = ["SEED_LIMIT", "assert_attitude_error", "assert_bias_converges", "assert_bounds", "assert_runs_close",
           "assert_step", "assert_tracking", "run_scenario", "make_system", "quadcosim_seed", "seed_of",
           "step_response"]
