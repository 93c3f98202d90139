"""Each finding's command, run as written, prints its value: ``python -m findings --verify-commands``.

A finding's ``command`` is what a user types, from the repository's root, to see its number. This
module runs every distinct command of the chosen findings exactly as written and reads its
standard output: each finding of the command must appear there as a printed number equal to its
value within ``max(tolerance, half a unit of its last printed decimal)``.

How a command is run:

- it is split as a shell would (:func:`shlex.split`); ``quadcosim`` is the console script next to
  the running interpreter (``python -m quadcosim.main`` when there is none), ``python`` the running
  interpreter;
- in a fresh temporary folder, so that what it writes (``results/...``, its ``--out``) stays out of
  the repository, with the repository's root on ``PYTHONPATH`` (its modules import as they do from
  the root);
- a folder ``logs/`` there links to ``$QUADCOSIM_FLIGHT_LOGS`` (the flight logs, named in the
  commands as they sit in ``logs/``), and the word ``DATA`` stands for ``$QUADCOSIM_REAL_DATA``
  (the real recordings); a command whose data are absent is skipped, not failed.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from findings import ROOT

LOGS_VARIABLE = "QUADCOSIM_FLIGHT_LOGS"  # the folder the commands name logs/
DATA_VARIABLE = "QUADCOSIM_REAL_DATA"  # the folder the commands name DATA
DATA_WORD = "DATA"
LOGS_FOLDER = "logs"
# any printed number: 12, -0.5, 3.64, 1.2e-05 (a date 2015-10-11 yields numbers too: extra ones do no harm)
PRINTED_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
RELATIVE_SLACK = 1e-9  # float noise on the rounding bound
STDERR_LINES = 5  # lines of a failed command's standard error kept in its report


@dataclass
class Verified:
    """One command's verification.

    Parameters
    ----------
    command : str
        The command as the findings write it.
    names : list of str
        The findings it should print.
    status : str
        ``"ok"`` (every finding printed), ``"missing"`` (some not printed), ``"failed"`` (a
        non-zero exit code), ``"skipped"`` (its data absent).
    missing : list of str
        The findings not printed, each with its value (empty when ``ok``).
    seconds : float
        Wall-clock time of the run (s).
    detail : str
        Why it was skipped, or its exit code and the end of its standard error.
    """

    command: str
    names: list[str]
    status: str = "ok"
    missing: list[str] = field(default_factory=list)
    seconds: float = 0.0
    detail: str = ""

    def line(self) -> str:
        """The report's line: status, time, command, and what is wrong."""
        text = f"{self.status:8s} {self.seconds:7.1f} s  {self.command}  ({len(self.names)} findings)"
        if self.missing:
            text += "\n           not printed: " + "; ".join(self.missing)
        if self.detail:
            text += "\n           " + self.detail.replace("\n", "\n           ")
        return text


def by_command(findings: dict[str, dict], groups=None) -> dict[str, list[dict]]:
    """The findings of ``groups`` (all when None) by their command, in findings order.

    Parameters
    ----------
    findings : dict
        Name -> finding (:func:`findings.load`).
    groups : sequence of str, optional
        Groups to keep.
    """
    out: dict[str, list[dict]] = {}
    for f in findings.values():
        if groups is None or f["group"] in groups:
            out.setdefault(f["command"], []).append(f)
    return out


def printed_numbers(text: str) -> list[float]:
    """Every number in ``text`` (a command's standard output)."""
    return [float(token) for token in PRINTED_NUMBER.findall(text)]  # each token holds a digit


def bound(finding: dict) -> float:
    """How far a printed number may sit from ``finding``'s value: its tolerance, or half a unit of
    its last printed decimal when that is larger (in the finding's unit)."""
    half_unit = 0.5 * 10.0 ** -finding["digits"]
    return max(finding["tolerance"], half_unit) * (1 + RELATIVE_SLACK) + 1e-12


def not_printed(findings: list[dict], output: str) -> list[str]:
    """The findings of ``findings`` whose value no number of ``output`` matches (:func:`bound`),
    each as ``name = value unit``."""
    numbers = printed_numbers(output)
    return [f"{f['name']} = {f['value']:.{f['digits'] + 2}f} {f['unit']}" for f in findings
            if not any(abs(x - f["value"]) <= bound(f) for x in numbers)]


def program(words: list[str]) -> list[str]:
    """The argument vector that runs the command ``words`` (split) with this interpreter.

    Parameters
    ----------
    words : list of str
        ``["quadcosim", "run", "tp", ...]`` or ``["python", "-m", "module", ...]``.

    Raises
    ------
    ValueError
        Neither a ``quadcosim`` nor a ``python`` command.
    """
    if words[0] == "quadcosim":
        script = Path(sys.executable).parent / "quadcosim"
        return [str(script), *words[1:]] if script.exists() else [sys.executable, "-m", "quadcosim.main", *words[1:]]
    if words[0] in ("python", "python3"):
        return [sys.executable, *words[1:]]
    raise ValueError(f"not a quadcosim or python command: {shlex.join(words)}")


def _data(words: list[str]) -> tuple[list[str], str]:
    """``words`` with ``DATA`` replaced by ``$QUADCOSIM_REAL_DATA``, and why it cannot run ('' if it can)."""
    if DATA_WORD not in words:
        return words, ""
    folder = os.environ.get(DATA_VARIABLE, "")
    if not folder or not Path(folder).is_dir():
        return words, f"the real recordings are absent (set {DATA_VARIABLE} to their folder)"
    return [folder if w == DATA_WORD else w for w in words], ""


def _rewrites(words: list[str]) -> str:
    """Why the command ``words`` may not be run here ('' if it may): ``python -m findings``
    (``python -m findings``) without ``--check`` rewrites the repository's findings.json and pages."""
    runs_findings = words[:3] == ["python", "-m", "findings"] or words[:2] == ["quadcosim", "findings"]
    if runs_findings and "--check" not in words:
        return "it would rewrite findings.json and the pages: a finding's command must only print (add --check)"
    return ""


def _workspace(folder: Path, words: list[str]) -> str:
    """Link ``folder/logs`` to the flight logs when ``words`` name one; why it cannot run ('' if it can)."""
    if not any(w.startswith(f"{LOGS_FOLDER}/") for w in words):
        return ""
    logs = os.environ.get(LOGS_VARIABLE, "")
    if not logs or not Path(logs).is_dir():
        return f"the flight logs are absent (set {LOGS_VARIABLE} to their folder)"
    (folder / LOGS_FOLDER).symlink_to(Path(logs).resolve(), target_is_directory=True)
    return ""


def _environment() -> dict[str, str]:
    """The process's environment with the repository's root first on ``PYTHONPATH``."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
    return env


def verify(command: str, findings: list[dict], timeout: float | None = None) -> Verified:
    """Run ``command`` as written (see the module docstring) and check it prints ``findings``.

    Parameters
    ----------
    command : str
        A finding's command.
    findings : list of dict
        The findings whose command it is.
    timeout : float, optional
        Seconds after which the run is stopped and counted as failed (none by default).

    Returns
    -------
    Verified
    """
    result = Verified(command, [f["name"] for f in findings])
    words, absent = _data(shlex.split(command))
    refused = _rewrites(words)
    if refused:
        result.status, result.detail, result.missing = "failed", refused, [f["name"] for f in findings]
        return result
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="quadcosim-verify-") as folder:
        absent = absent or _workspace(Path(folder), words)
        if absent:
            result.status, result.detail = "skipped", absent
            return result
        try:
            run = subprocess.run(program(words), cwd=folder, env=_environment(), capture_output=True, text=True,
                                 timeout=timeout, stdin=subprocess.DEVNULL)
        except subprocess.TimeoutExpired:
            result.status, result.detail = "failed", f"stopped after {timeout:g} s"
            result.missing = [f["name"] for f in findings]
            result.seconds = time.perf_counter() - start
            return result
    result.seconds = time.perf_counter() - start
    result.missing = not_printed(findings, run.stdout)
    if run.returncode != 0:
        tail = "\n".join(run.stderr.strip().splitlines()[-STDERR_LINES:])
        result.status, result.detail = "failed", f"exit code {run.returncode}: {tail}"
    elif result.missing:
        result.status = "missing"
    return result


def verify_all(findings: dict[str, dict], groups=None, timeout: float | None = None, report=print,
               matching: str = "") -> list[Verified]:
    """Verify every distinct command of the findings of ``groups``, reporting each as it ends.

    Parameters
    ----------
    findings : dict
        Name -> finding (:func:`findings.load`).
    groups : sequence of str, optional
        Groups to verify (all when None).
    timeout : float, optional
        Per command, seconds (none by default).
    report : callable
        Called with each command's :meth:`Verified.line`.
    matching : str
        Only the commands containing this text (all when empty).

    Returns
    -------
    list of Verified
    """
    results = []
    for command, found in by_command(findings, groups).items():
        if matching not in command:
            continue
        report(f"running  {command}")
        results.append(verify(command, found, timeout))
        report(results[-1].line())
    return results


def summary(results: list[Verified]) -> str:
    """One line: how many commands were ok, missing a finding, failed, skipped, and the time taken.

    Parameters
    ----------
    results : list of Verified
        As :func:`verify_all` returns them.
    """
    counts = {s: sum(r.status == s for r in results) for s in ("ok", "missing", "failed", "skipped")}
    return (f"{len(results)} commands: " + ", ".join(f"{n} {s}" for s, n in counts.items())
            + f"; {sum(r.seconds for r in results):.0f} s")
