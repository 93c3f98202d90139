"""Where compiled artefacts go: ``build/`` in this checkout, a named folder, or (installed) a
per-user cache; a plant FMU missing from its default folder is built on first use, once."""

import os
from pathlib import Path

from quadcosim.fmus import build_root, fmu_path

from quadcosim import fmus
from quadcosim.infra import folders

ROOT = Path(__file__).resolve().parent.parent


def test_a_checkout_builds_into_its_own_build_folder(monkeypatch):
    monkeypatch.delenv("QUADCOSIM_BUILD_DIR", raising=False)
    assert build_root() == ROOT / "build"


def test_an_installed_package_builds_into_the_user_cache(monkeypatch, tmp_path):
    monkeypatch.delenv("QUADCOSIM_BUILD_DIR", raising=False)
    monkeypatch.setattr(folders, "_checkout", lambda: None)
    folders._build_root.cache_clear()
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert build_root() == tmp_path / "quadcosim" / folders._version()
    folders._build_root.cache_clear()


def test_a_missing_fmu_is_built_on_first_use_then_reused(monkeypatch, tmp_path, capsys):
    monkeypatch.delenv("QUADCOSIM_FMU_DIR", raising=False)
    monkeypatch.setenv("QUADCOSIM_BUILD_DIR", str(tmp_path))
    path = fmu_path("IMU")
    assert path == tmp_path / "fmus" / "IMU.fmu" and path.is_file()
    assert "building the FMU IMU" in capsys.readouterr().err
    built = path.stat().st_mtime_ns
    assert fmu_path("IMU").stat().st_mtime_ns == built
    assert capsys.readouterr().err == ""
    newer = max(source.stat().st_mtime for source in fmus.fmu_sources("IMU")) + 10
    os.utime(path, (newer - 20, newer - 20))  # a source edited after the build: rebuilt by the next process
    fmus._checked.clear()
    fmu_path("IMU")
    assert "building the FMU IMU" in capsys.readouterr().err
