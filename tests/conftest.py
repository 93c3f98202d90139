"""Shared fixtures: the FMUs are built once per session if they are missing; a test's figures
are closed after it, so no test sees another's."""

import os
import sys
from pathlib import Path

import pytest

# The real flight logs beside the repository, for the flight-log findings group.
os.environ.setdefault("QUADCOSIM_FLIGHT_LOGS",
                      str(Path(__file__).resolve().parents[1].parent / "shared" / "data" / "flightlogs"))

from quadcosim.fmus import MODELS, default_fmu_dir


@pytest.fixture(scope="session", autouse=True)
def built_fmus():
    from quadcosim.fmus.build import FMI_VERSIONS, build_all, fmu_file

    if not all(fmu_file(m, default_fmu_dir(), v).is_file() for m in MODELS for v in FMI_VERSIONS):
        build_all(default_fmu_dir(), verbose=False)
    return default_fmu_dir()


@pytest.fixture(autouse=True)
def figures_closed_after_each_test():
    yield
    pyplot = sys.modules.get("matplotlib.pyplot")
    if pyplot:
        pyplot.close("all")
