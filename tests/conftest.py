"""Shared fixtures: the FMUs are built once per session if they are missing."""

import pytest

from fmus import MODELS, default_fmu_dir


@pytest.fixture(scope="session", autouse=True)
def built_fmus():
    missing = [m for m in MODELS if not (default_fmu_dir() / f"{m}.fmu").is_file()]
    if missing:
        from fmus.build import build_all

        build_all(verbose=False)
    return default_fmu_dir()
