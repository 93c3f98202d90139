"""The README's numbers are the committed findings, and the findings are what the code measures.

- every number in a findings passage of the README (and of docs/) is a committed finding at its
  rounding, and every finding of the passage's scope is printed in it;
- a committed value changed beyond its rounding, or beyond its tolerance, fails;
- each group's fast subset, re-run, gives the committed values within their tolerances;
- a group whose data are absent is skipped, its committed values kept.
"""

import json
import re
import sys
import types

import pytest
from helpers import documentation

import findings as findings
from findings import readme
from findings.__main__ import main as findings_main

COMMITTED = findings.load()


def test_findings_file_is_committed_and_well_formed():
    assert COMMITTED, "findings.json is missing: run `python -m findings`"
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
        monkeypatch.setitem(sys.modules, f"findings.{name}", types.SimpleNamespace(compute=compute))
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
    monkeypatch.setitem(sys.modules, "findings.bad", types.SimpleNamespace(
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


# commands run as written and checked to print their findings in CI: the fast ones (seconds each;
# `python -m findings --verify-commands` runs them all, the robustness study included)
PRINT_CHECKED = ("flight.tilt.", "flight.tilt_without_drag.", "flight.wind.tilt", "rig.", "lab.linear_quasi_gt.",
                 "lab.ablation.ideal_", "lab.passive_convergence.reel.k100.",
                 "lab.triad_bias.times_true.", "infrared.slides.", "flight.wind.offset_",
                 "flightlogs.quad.internal.current.explained_half_b", "flightlogs.replay.b1.",
                 "records.tp_npz_mb", "log_info.", "plant.", "excerpt.")


def _checked_commands() -> dict[str, list[dict]]:
    from findings import commands

    return {c: found for c, found in commands.by_command(COMMITTED).items()
            if any(f["name"].startswith(PRINT_CHECKED) for f in found)}


@pytest.mark.slow
@pytest.mark.parametrize("command", sorted(_checked_commands()))
def test_a_findings_command_run_as_written_prints_its_findings(command):
    from findings import commands

    verified = commands.verify(command, _checked_commands()[command])
    if verified.status == "skipped":
        pytest.skip(verified.detail)
    assert (verified.status, verified.missing, verified.detail) == ("ok", [], "")


def _finding(name: str, value: float, tolerance: float, digits: int, command: str = "python -m x") -> dict:
    return findings.finding(name, value, "deg", command, tolerance, digits) | {"group": "g"}


def test_verifier_reads_a_value_printed_at_its_digits_or_within_its_tolerance():
    from findings import commands

    out = "  wind_tilt_final_deg: 4.1179\n  rms_error_deg: [0, 0.012224, -3.5e-05]\n  ratio 12%"
    found = [_finding("g.tilt", 4.117926, 5e-5, 4), _finding("g.rms", 0.0122216, 1e-5, 4),
             _finding("g.small", -3.46e-5, 1e-6, 6), _finding("g.ratio", 12.4, 0.1, 0)]
    assert commands.not_printed(found, out) == []
    moved = [_finding("g.tilt", 4.11801, 5e-5, 4), _finding("g.rms", 0.0123, 1e-5, 4),
             _finding("g.ratio", 12.6, 0.1, 0)]
    assert [m.split(" = ")[0] for m in commands.not_printed(moved, out)] == ["g.tilt", "g.rms", "g.ratio"]


def test_verifier_refuses_a_command_that_rewrites_the_findings_and_skips_absent_data(monkeypatch):
    from findings import commands

    refused = commands.verify("python -m findings flight", [_finding("g.a", 1.0, 0.1, 1)])
    assert refused.status == "failed" and "--check" in refused.detail and refused.missing == ["g.a"]
    monkeypatch.delenv("QUADCOSIM_REAL_DATA", raising=False)
    absent = commands.verify("python -m quadcosim.benchmarks.real_recordings DATA", [_finding("g.b", 1.0, 0.1, 1)])
    assert absent.status == "skipped" and "QUADCOSIM_REAL_DATA" in absent.detail
    monkeypatch.delenv("QUADCOSIM_FLIGHT_LOGS", raising=False)
    assert commands.verify("quadcosim log replay logs/x.ulg", [_finding("g.c", 1.0, 0.1, 1)]).status == "skipped"


def test_verifier_runs_a_command_in_a_scratch_folder_and_names_what_it_does_not_print(tmp_path):
    from findings import commands

    printed = "quadcosim list --parameters IMU"  # prints the IMU's parameters: the gyro bias default 0
    verified = commands.verify(printed, [_finding("g.zero", 0.0, 0.0, 0, printed),
                                         _finding("g.absent", 123456.789, 1e-3, 3, printed)])
    assert verified.status == "missing" and verified.missing == ["g.absent = 123456.78900 deg"]
    assert commands.verify("quadcosim run no-such-scenario", [_finding("g.x", 1.0, 0.1, 1)]).status == "failed"


def test_the_readme_states_the_default_result_format():
    from quadcosim.main import parser

    default = parser().parse_args(["run", "tp"]).format
    stated = re.search(r"`--format\s+npz,mat,csv` the files written \(default `([^`]*)` alone\)", documentation())
    assert stated is not None and stated.group(1) == default
