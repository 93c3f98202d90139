"""Item 13: the findings (a maintainer's tool) never write into an installed copy, and a check that
checked nothing (every group's data absent) does not pass for one that found no difference."""

import sys
import types

import pytest

import findings as findings
from findings.__main__ import main as findings_main


def test_an_installed_copy_is_refused_and_left_as_it_was(tmp_path, monkeypatch, capsys):
    installed = tmp_path / "site-packages"  # the package's parent folder, without the checkout's files
    installed.mkdir()
    monkeypatch.setattr(findings, "ROOT", installed)
    for argv in ([], ["--check"], ["lab", "--quick"]):
        assert findings_main([*argv, "--out", str(installed / "findings.json")]) == 2
        assert f"is installed in {installed} (no pyproject.toml, README.md and docs/ there)" in capsys.readouterr().err
    assert list(installed.iterdir()) == []


def test_a_check_of_groups_whose_data_are_all_absent_fails(tmp_path, monkeypatch, capsys):
    def absent(quick=False):
        raise FileNotFoundError("no recordings in /data/broad (set QUADCOSIM_DATA)")

    monkeypatch.setitem(sys.modules, "findings.absent", types.SimpleNamespace(compute=absent))
    monkeypatch.setattr(findings, "GROUPS", ("absent",))
    out = tmp_path / "findings.json"
    findings.save({}, out)
    assert findings_main(["--out", str(out), "--check"]) == 1
    captured = capsys.readouterr()
    assert "nothing was checked: every group asked for was skipped (absent)" in captured.err
    assert "0 differences" not in captured.out


@pytest.mark.parametrize("argv", [["--check"], ["--no-readme"]])
def test_a_checkout_still_runs(argv, tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "findings.present", types.SimpleNamespace(
        compute=lambda quick=False: [findings.finding("present.x", 2.5, "s", "quadcosim run x", 0.1, 1)]))
    monkeypatch.setattr(findings, "GROUPS", ("present",))
    out = tmp_path / "findings.json"
    findings.save({"present.x": findings.finding("present.x", 2.5, "s", "quadcosim run x", 0.1, 1)
                   | {"group": "present"}}, out)
    assert findings_main([*argv, "--out", str(out)]) == 0


@pytest.mark.parametrize("kind", ["folder", "missing folder", "fifo"])
def test_an_output_the_writer_refuses_is_refused_before_any_group_runs(tmp_path, monkeypatch, capsys, kind):
    import os

    ran = []
    monkeypatch.setattr(findings, "compute_group", lambda group, quick=False: ran.append(group) or [])
    out = {"folder": tmp_path, "missing folder": tmp_path / "absent" / "f.json", "fifo": tmp_path / "f.fifo"}[kind]
    if kind == "fifo":
        os.mkfifo(out)
    assert findings_main(["excerpt", "--quick", "--no-readme", "--out", str(out)]) == 2  # a traceback before
    err = capsys.readouterr().err
    assert err.startswith(f"python -m findings: {'--out ' if kind == 'folder' else ''}{out}") and not ran
