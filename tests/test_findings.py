"""The README's numbers are the committed findings, and the findings are what the code measures.

- every number in a findings passage of the README (and of docs/) is a committed finding at its
  rounding, and every finding of the passage's scope is printed in it;
- a committed value changed beyond its rounding, or beyond its tolerance, fails;
- each group's fast subset, re-run, gives the committed values within their tolerances;
- a group whose data are absent is skipped, its committed values kept.
"""

import json
import re
import shlex
import sys
import types

import pytest
from helpers import documentation

import scenarios.findings as findings
from scenarios.findings import readme
from scenarios.findings.__main__ import main as findings_main

COMMITTED = findings.load()


def test_findings_file_is_committed_and_well_formed():
    assert COMMITTED, "findings.json is missing: run `python -m scenarios.findings`"
    for f in COMMITTED.values():
        assert findings.check(f, f["group"]) == f
        assert f["group"] in findings.GROUPS
        assert f["command"].startswith(("quadcosim ", "python -m ")), f["name"]


@pytest.mark.parametrize("page", readme.pages(findings.ROOT), ids=lambda p: p.name)
def test_every_number_of_a_findings_passage_is_a_committed_finding(page):
    assert readme.problems(page, COMMITTED) == []


def test_every_committed_finding_is_printed_in_a_passage():
    printed = set()
    for page in readme.pages(findings.ROOT):
        for passage in readme.passages(page):
            printed |= {f["name"] for f in readme.in_scope(passage.scope, COMMITTED)}
    assert sorted(set(COMMITTED) - printed) == []


def _moved(name: str, by: float) -> dict:
    moved = {k: dict(v) for k, v in COMMITTED.items()}
    moved[name]["value"] += by
    return moved


@pytest.mark.parametrize("name", sorted(COMMITTED))
def test_a_committed_value_moved_beyond_its_rounding_parts_from_the_readme(name):
    last_decimal = 10.0 ** -COMMITTED[name]["digits"]
    moved = _moved(name, 1.01 * last_decimal)
    problems = [p for page in readme.pages(findings.ROOT) for p in readme.problems(page, moved)]
    assert problems  # the README check fails (naming this finding, or the one whose number it took)


def test_a_value_moved_beyond_its_tolerance_is_a_difference():
    name, f = next(iter(COMMITTED.items()))
    assert findings.differences([dict(f)], COMMITTED) == []
    moved = dict(f, value=f["value"] + 1.01 * f["tolerance"] + 1e-12)
    (line,) = findings.differences([moved], COMMITTED)
    assert name in line and "tolerance" in line


PAGE = """Intro 7 is outside.
<!-- findings:g.a, g.b -->
The tilt is 4.994° (`tilt_deg=5`, eq. 9) against [5.1] in the paper, speed 3.64 m/s, x100 and 3S.
<!-- /findings -->
"""


def _findings(a: float, b: float) -> dict:
    return {"g.a": findings.finding("g.a", a, "deg", "quadcosim run x", 1e-3, 3) | {"group": "g"},
            "g.b": findings.finding("g.b", b, "m/s", "quadcosim run x", 1e-2, 2) | {"group": "g"}}


def test_checker_reads_inputs_and_citations_as_such_and_finds_strays(tmp_path):
    page = tmp_path / "README.md"
    page.write_text(PAGE)
    assert readme.problems(page, _findings(4.9941, 3.636)) == []
    stray, missing = readme.problems(page, _findings(4.9941, 3.70))
    assert "README.md:3: 3.64 is no finding of g.a, g.b" in stray and "g.b = 3.70 m/s is not printed" in missing
    page.write_text(PAGE.replace("speed 3.64 m/s", "speed 3.64 m/s and 12.5"))
    assert any("12.5 is no finding" in p for p in readme.problems(page, _findings(4.9941, 3.636)))
    page.write_text(PAGE.replace(", speed 3.64 m/s", ""))
    (missing,) = readme.problems(page, _findings(4.9941, 3.636))
    assert "g.b = 3.64 m/s is not printed" in missing


STRAYS = """# 2. Set-up

In 2024, with Python 3.12 and FMI 2.0, `tilt_deg=5` [5.1] as in eq. 9:

1. first
<!-- inputs -->
Roll of 20° at 0.4 Hz.
<!-- /inputs -->

```sh
quadcosim run tp --set duration=30
```
<!-- findings:g.a -->
Measured 4.994°.
<!-- /findings -->
The fitted lag is 4.257 s.
"""


def test_a_number_outside_findings_passages_is_a_stray_unless_an_input(tmp_path):
    page = tmp_path / "guide.md"
    page.write_text(STRAYS)
    (stray,) = readme.strays(page)
    assert stray.startswith("guide.md:16: 4.257 is stated outside a findings passage")
    page.write_text(STRAYS.replace("The fitted lag is 4.257 s.", "The fitted lag is in `metrics.json`."))
    assert readme.strays(page) == []
    page.write_text(STRAYS.replace("<!-- /inputs -->", "").replace("The fitted lag is 4.257 s.", ""))
    assert [s.split(":")[1] for s in readme.strays(page)] == ["7", "7"]  # 20 and 0.4, no longer inputs


@pytest.mark.parametrize("page", readme.pages(findings.ROOT), ids=lambda p: p.name)
def test_a_page_states_measured_numbers_only_in_findings_passages(page):
    assert readme.strays(page) == []


def test_unclosed_passage_is_refused(tmp_path):
    page = tmp_path / "README.md"
    page.write_text(PAGE.replace("<!-- /findings -->", ""))
    with pytest.raises(ValueError, match="not closed"):
        readme.passages(page)


def test_rewrite_regenerates_the_numbers_from_new_values(tmp_path):
    page = tmp_path / "README.md"
    page.write_text(PAGE)
    assert readme.rewrite(page, _findings(4.9941, 3.636), _findings(4.9872, 3.61)) == []
    text = page.read_text()
    assert "is 4.987° (`tilt_deg=5`, eq. 9) against [5.1]" in text and "speed 3.61 m/s" in text
    assert readme.problems(page, _findings(4.9872, 3.61)) == []


@pytest.fixture
def groups(monkeypatch):
    """Two groups in the registry: one that measures, one whose data are absent."""
    def measured(quick=False):
        return [findings.finding("present.x", 2.5, "s", "quadcosim run x", 0.1, 1)]

    def absent(quick=False):
        raise FileNotFoundError("no recordings in /data/broad (set QUADCOSIM_DATA)")

    for name, compute in (("present", measured), ("absent", absent)):
        monkeypatch.setitem(sys.modules, f"scenarios.findings.{name}", types.SimpleNamespace(compute=compute))
    monkeypatch.setattr(findings, "GROUPS", ("present", "absent"))


def test_a_group_without_its_data_is_skipped_and_keeps_its_committed_values(groups, tmp_path, capsys):
    out = tmp_path / "findings.json"
    kept = findings.finding("absent.y", 1.0, "deg", "quadcosim run y", 0.1, 1) | {"group": "absent"}
    findings.save({"absent.y": kept}, out)
    assert findings_main(["--out", str(out), "--no-readme"]) == 0
    written = {f["name"]: f for f in json.loads(out.read_text())["findings"]}
    assert written["absent.y"] == kept and written["present.x"]["value"] == 2.5
    assert "absent: skipped (data absent: no recordings in /data/broad" in capsys.readouterr().err
    assert findings_main(["--out", str(out), "--check"]) == 0
    assert findings_main(["nothing", "--out", str(out)]) == 2


def test_a_malformed_finding_is_refused_naming_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "scenarios.findings.bad", types.SimpleNamespace(
        compute=lambda quick=False: [{"name": "bad.z", "value": float("nan"), "unit": "", "command": "c",
                                      "tolerance": 0, "digits": 1}]))
    monkeypatch.setattr(findings, "GROUPS", ("bad",))
    with pytest.raises(findings.FindingError, match="bad.z: value nan is not finite"):
        findings.compute_group("bad")


@pytest.mark.slow
@pytest.mark.parametrize("group", findings.GROUPS)
def test_quick_findings_reproduce_the_committed_values(group):
    try:
        computed = findings.compute_group(group, quick=True)
    except findings.Skipped as reason:
        pytest.skip(f"{group}: {reason}")
    if not computed:
        pytest.skip(f"{group} has no quick subset (each of its runs takes minutes)")
    assert findings.differences(computed, COMMITTED) == []


# findings whose command, run as written, is checked to print them (a few fast ones: CI time)
PRINT_CHECKED = ("flight.tilt.", "rig.", "lab.linear_quasi_gt.", "records.tp_npz_mb", "log_info.")
PRINTED_NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")


@pytest.mark.slow
@pytest.mark.parametrize("command", sorted({f["command"] for n, f in COMMITTED.items() if n.startswith(PRINT_CHECKED)}))
def test_a_findings_command_run_as_written_prints_its_findings(command, tmp_path, capsys, monkeypatch):
    import os
    from pathlib import Path

    from scenarios.cli import main

    words = shlex.split(command)
    assert words[0] == "quadcosim"
    if any(w.startswith("logs/") for w in words):  # the logs as the commands name them, in a folder logs/
        (tmp_path / "logs").symlink_to(Path(os.environ["QUADCOSIM_FLIGHT_LOGS"]).resolve())
        monkeypatch.chdir(tmp_path)
    out = ["--out", str(tmp_path / "run")] if words[1] == "run" else []  # a run's files go to tmp_path
    assert main(words[1:] + out) == 0
    shown = [float(x) for x in PRINTED_NUMBER.findall(capsys.readouterr().out)]
    for f in (f for f in COMMITTED.values() if f["command"] == command):
        assert any(abs(x - f["value"]) <= f["tolerance"] for x in shown), f"{f['name']} not printed by {command}"


def test_the_readme_states_the_default_result_format():
    from scenarios.cli import parser

    default = parser().parse_args(["run", "tp"]).format
    stated = re.search(r"`--format\s+npz,mat,csv` the files written \(default `([^`]*)` alone\)", documentation())
    assert stated is not None and stated.group(1) == default


# `python -m` commands checked the same way (fast ones: a few seconds each)
MODULE_PRINT_CHECKED = ("plant.", "excerpt.")


@pytest.mark.slow
@pytest.mark.parametrize("command", sorted({f["command"] for n, f in COMMITTED.items()
                                            if n.startswith(MODULE_PRINT_CHECKED)}))
def test_a_python_module_findings_command_run_as_written_prints_its_findings(command):
    import subprocess

    words = shlex.split(command)
    assert words[:2] == ["python", "-m"]
    printed = subprocess.run([sys.executable, *words[1:]], capture_output=True, text=True, check=True,
                             cwd=findings.ROOT).stdout
    shown = [float(x) for x in PRINTED_NUMBER.findall(printed)]
    for f in (f for f in COMMITTED.values() if f["command"] == command):
        assert any(abs(x - f["value"]) <= f["tolerance"] for x in shown), f"{f['name']} not printed by {command}"
