"""The README's numbers checked against ``findings.json``, and rewritten from it.

A passage of the README (or of a page under ``docs/``) whose numbers are findings sits between
``<!-- findings:SCOPE -->`` and ``<!-- /findings -->``. ``SCOPE`` is a comma-separated list of
finding names or name prefixes (a group, ``metge``, or part of one, ``flight.tilt``). In a passage:

- every number is the value of a finding of its scope, printed with that finding's ``digits``
  (rounded: within half a unit of the last decimal);
- every finding of its scope is printed in it at least once;
- a number that is not a finding is an input or a citation: it sits in a code span
  (`` `tilt_deg=5` ``), in math (``$2 k_m \\omega$``, ``$$...$$``: a formula's constants), in
  square brackets (a paper's value, ``[11.1]``), or after a reference word (``eq. 9``,
  ``Table 1``).

So a finding whose value moves by more than its rounding parts from the README, and the test
fails. :func:`rewrite` replaces, in every passage, each number printed from an old value by the
new value: the README is regenerated from the findings, not typed.

Outside the passages a page states no measurement (:func:`strays`): a number there is an input
or a citation as above, a fenced code block's, a heading's or list item's enumeration, a year, a
version or degree after its name (``Python 3.12``), or it sits in an *inputs* passage, between
``<!-- inputs -->`` and ``<!-- /inputs -->``, which holds settings, definitions and thresholds.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

BEGIN = re.compile(r"<!--\s*findings:\s*([^>]*?)\s*-->")
END = "<!-- /findings -->"
# a number not glued to a word (x100, 3S, 2x2 are not numbers here); a sign when it stands alone
NUMBER = re.compile(r"(?<![\w.\-−+])([+\-−]?)(\d+(?:\.\d+)?(?:e[+\-]?\d+)?)(?![\w.]*\w)")
CODE_OR_CITATION = re.compile(r"`[^`]*`|(?s:\$\$.*?\$\$)|\$[^$\n]+\$|\[[^\]]*\]\(?[^)\s]*\)?|<!--.*?-->")
# a number after one of these words cites a reference (eq. 9, Table 1): it is not checked
CITED = ("eq.", "eqs.", "Table", "Figure", "Fig.", "section", "Section")
# outside findings passages: inputs passages, fenced code, enumerations, years, versions
INPUTS = re.compile(r"<!--\s*inputs\s*-->.*?<!--\s*/inputs\s*-->", re.S)
FENCE = re.compile(r"^(`{3,}|~{3,})[^\n]*\n.*?^\1", re.S | re.M)
ENUMERATION = re.compile(r"^[ \t]*(?:#+[ \t]+|[-*][ \t]+)?\d+\.[ \t]", re.M)
YEAR = re.compile(r"(?:19|20)\d\d")
# a number in a name: a version (Python 3.12, FMI 2.0, Copter 3.4) or a degree (Master 2)
NAMED = ("Python", "FMI", "Copter", "ArduPilot", "PX4", "Sphinx", "Master")


@dataclass
class Passage:
    """One ``findings`` passage of a page.

    Parameters
    ----------
    path : pathlib.Path
        The page.
    scope : tuple of str
        Finding names or name prefixes.
    line : int
        Line of the opening marker (from 1).
    start : int
        Offset of the passage's text in the page.
    text : str
        The passage, markers excluded.
    """

    path: Path
    scope: tuple[str, ...]
    line: int
    start: int  # offset of the text in the page
    text: str


def passages(path) -> list[Passage]:
    """The findings passages of the Markdown page ``path``.

    Raises
    ------
    ValueError
        A passage not closed, or one opened inside another.
    """
    path = Path(path)
    page = path.read_text()
    found, position = [], 0
    while (match := BEGIN.search(page, position)) is not None:
        end = page.find(END, match.end())
        nested = BEGIN.search(page, match.end(), end if end >= 0 else len(page))
        line = page.count("\n", 0, match.start()) + 1
        if end < 0 or nested is not None:
            raise ValueError(f"{path}:{line}: findings passage {match.group(1)!r} not closed by {END} "
                             "before the next one")
        scope = tuple(s.strip() for s in match.group(1).split(",") if s.strip())
        found.append(Passage(path, scope, line, match.end(), page[match.end():end]))
        position = end + len(END)
    return found


def numbers(text: str) -> list[tuple[int, str]]:
    """(offset, number as printed, sign included) of every checked number in ``text``: those
    outside code spans, brackets and comments, and not after a reference word (``eq. 9``)."""
    masked = CODE_OR_CITATION.sub(lambda m: " " * len(m.group(0)), text)
    found = []
    for match in NUMBER.finditer(masked):
        before = masked[:match.start()].split()
        if before and before[-1] in CITED:
            continue
        found.append((match.start(), (match.group(1).replace("−", "-") + match.group(2))))
    return found


def printed(finding: dict) -> str:
    """``finding``'s value as the README prints it: ``digits`` decimals (a value that rounds to
    zero is printed without a sign, so that -0.3 and 0.2 at no decimal both print 0)."""
    shown = f"{finding['value']:.{finding['digits']}f}"
    return shown.lstrip("-") if float(shown) == 0 else shown


def matches(token: str, finding: dict) -> bool:
    """Whether the printed number ``token`` is ``finding``'s value at its ``digits``."""
    decimals = len(token.split(".")[1]) if "." in token else 0
    if "e" in token.lower() or decimals != finding["digits"]:
        return token == printed(finding)
    return abs(float(token) - finding["value"]) <= 0.5 * 10.0 ** -decimals * (1 + 1e-9) + 1e-12


def in_scope(scope: tuple[str, ...], findings: dict[str, dict]) -> list[dict]:
    """The findings a scope names: an exact name, or every name under a prefix."""
    return [f for name, f in findings.items() if any(name == s or name.startswith(s + ".") for s in scope)]


def problems(path, findings: dict[str, dict]) -> list[str]:
    """What in page ``path`` parts from ``findings``: one line each, naming the line of the page.

    Parameters
    ----------
    path : str or pathlib.Path
        A Markdown page.
    findings : dict
        Name -> finding (:func:`findings.load`).

    Returns
    -------
    list of str
        Empty when every passage agrees.
    """
    lines = []
    for passage in passages(path):
        where = f"{passage.path.name}:{passage.line}"
        scoped = in_scope(passage.scope, findings)
        if not scoped:
            lines.append(f"{where}: scope {', '.join(passage.scope)} names no finding of findings.json")
            continue
        shown = numbers(passage.text)
        for offset, token in shown:
            if not any(matches(token, f) for f in scoped):
                line = passage.line + passage.text.count("\n", 0, offset)
                lines.append(f"{passage.path.name}:{line}: {token} is no finding of {', '.join(passage.scope)} "
                             "(a measured number: add it to its group in findings/ and run "
                             "`python -m findings`; an input: put it in a code span)")
        for f in unprinted(scoped, [token for _, token in shown]):
            lines.append(f"{where}: {f['name']} = {printed(f)} {f['unit']} is not printed in the passage "
                         f"{', '.join(passage.scope)} (its command: {f['command']})")
    return lines


def unprinted(scoped: list[dict], tokens: list[str]) -> list[dict]:
    """The findings that get no printed number of their own: a maximum matching of findings to
    the numbers that print them (Kuhn's augmenting paths), so that two findings of one value
    need two numbers, and a finding moved onto another's value is still missed.

    Parameters
    ----------
    scoped : list of dict
        The passage's findings.
    tokens : list of str
        The passage's numbers, as printed.

    Returns
    -------
    list of dict
        The findings left without a number.
    """
    candidates = [[j for j, token in enumerate(tokens) if matches(token, f)] for f in scoped]
    owner: dict[int, int] = {}

    def assign(i: int, seen: set) -> bool:
        for j in candidates[i]:
            if j not in seen:
                seen.add(j)
                if j not in owner or assign(owner[j], seen):
                    owner[j] = i
                    return True
        return False

    return [f for i, f in enumerate(scoped) if not assign(i, set())]


def strays(path) -> list[str]:
    """The numbers of page ``path`` stated outside its findings passages as if measured: one line
    each, naming the line of the page and the fix.

    A number outside the findings passages is accepted as an input or a citation (see the
    module's docstring); any other is a measurement with no finding behind it.

    Parameters
    ----------
    path : str or pathlib.Path
        A Markdown page.

    Returns
    -------
    list of str
        Empty when the page states every measurement inside a findings passage.
    """
    path = Path(path)
    page = path.read_text()

    def blank(text: str) -> str:  # spaces in place of text, its line breaks kept
        return re.sub(r"[^\n]", " ", text)

    masked = page
    for passage in passages(path):
        end = passage.start + len(passage.text)
        masked = masked[:passage.start] + blank(passage.text) + masked[end:]
    for pattern in (INPUTS, FENCE, ENUMERATION):
        masked = pattern.sub(lambda match: blank(match.group(0)), masked)
    lines = []
    for offset, token in numbers(masked):
        before = masked[:offset].split()
        if YEAR.fullmatch(token) or (before and before[-1] in NAMED):
            continue
        line = masked.count("\n", 0, offset) + 1
        lines.append(f"{path.name}:{line}: {token} is stated outside a findings passage (a measured number: "
                     "add it to a group in findings/ and put it in a `<!-- findings:NAME -->` passage; "
                     "an input: a code span or an `<!-- inputs -->` passage)")
    return lines


def pages(root) -> list[Path]:
    """The README and the pages under ``docs/`` of the repository at ``root``, those the docs
    build writes (``_build``, ``_generated``: a run's own ``table1.md``) left out."""
    root = Path(root)
    return [root / "README.md", *sorted(p for p in (root / "docs").rglob("*.md")
                                        if not {"_build", "_generated"} & set(p.relative_to(root).parts))]


def rewrite(path, old: dict[str, dict], new: dict[str, dict]) -> list[str]:
    """Rewrite in page ``path`` every number printed from an ``old`` finding with its ``new`` value.

    Parameters
    ----------
    path : str or pathlib.Path
        A Markdown page.
    old, new : dict
        Name -> finding, before and after a run of the findings.

    Returns
    -------
    list of str
        The numbers that could not be rewritten (printed from no old finding, or from several
        old findings whose new values differ); empty when the page is up to date.
    """
    from quadcosim.infra.files import write_text

    path = Path(path)
    page = path.read_text()
    edits, unresolved = [], []
    for passage in passages(path):
        scoped = [f for f in in_scope(passage.scope, old) if f["name"] in new]
        for offset, token in numbers(passage.text):
            sources = {printed(new[f["name"]]) for f in scoped if matches(token, f)}
            if len(sources) == 1:
                replacement = sources.pop()
                if token.startswith("+") and not replacement.startswith("-"):
                    replacement = "+" + replacement
                edits.append((passage.start + offset, len(token), replacement))
            else:
                line = passage.line + passage.text.count("\n", 0, offset)
                unresolved.append(f"{path.name}:{line}: {token} " + ("is printed from no finding" if not sources else
                                                                    f"is ambiguous ({', '.join(sorted(sources))})"))
    for start, length, replacement in sorted(edits, reverse=True):
        page = page[:start] + replacement + page[start + length:]
    write_text(path, page)
    return unresolved
