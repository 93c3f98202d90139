"""``python -m findings``: run the README's findings.

Runs every group of :data:`findings.GROUPS` (or those named), prints each finding
with its command, writes ``findings.json`` and rewrites the README's numbers from it. A
skipped group (its data absent) keeps its committed values and is said so. ``--check``
writes nothing and exits 1 when a value moved by more than its tolerance. ``--verify-commands``
runs each finding's command as written and exits 1 when one does not print its findings
(:mod:`findings.commands`).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import findings as findings
from findings import readme


def parser() -> argparse.ArgumentParser:
    """The command's argument parser."""
    from quadcosim.scenarios.shown import PlainHelp

    p = argparse.ArgumentParser(prog="python -m findings", description=__doc__,
                                formatter_class=PlainHelp)
    p.add_argument("groups", nargs="*", metavar="GROUP",
                   help=f"groups to run (default all: {', '.join(findings.GROUPS)})")
    p.add_argument("--quick", action="store_true", help="each group's fast subset (seconds to a minute)")
    p.add_argument("--check", action="store_true",
                   help="compare with the committed findings.json; write nothing; exit 1 on a difference")
    p.add_argument("--out", type=Path, default=findings.FINDINGS_FILE, help="findings file (default: the repository's)")
    p.add_argument("--no-readme", action="store_true", help="leave the README and docs/ as they are")
    p.add_argument("--verify-commands", action="store_true",
                   help="run each distinct command of the committed findings (of GROUPs) as written, in a "
                        "temporary folder, and check it prints their values; exit 1 if one does not")
    p.add_argument("--timeout", type=float, default=None, metavar="SECONDS",
                   help="with --verify-commands: stop a command after this long and count it failed")
    p.add_argument("--matching", default="", metavar="TEXT",
                   help="with --verify-commands: only the commands containing TEXT")
    return p


def run(groups, quick: bool) -> tuple[list[dict], dict[str, str]]:
    """The findings of ``groups`` and the groups skipped (group -> reason), printed as they come.

    Parameters
    ----------
    groups : sequence of str
        Groups of :data:`findings.GROUPS`.
    quick : bool
        Each group's fast subset.
    """
    computed, skipped = [], {}
    for group in groups:
        print(f"[{group}]", flush=True)
        try:
            found = findings.compute_group(group, quick=quick)
        except findings.Skipped as reason:
            skipped[group] = str(reason)
            print(f"  skipped: {reason}", flush=True)
            continue
        for f in found:
            print(f"  {f['name']} = {readme.printed(f)} {f['unit']}    ({f['command']})", flush=True)
        computed += found
    return computed, skipped


def verify_commands(committed: dict, groups, timeout, matching: str = "") -> int:
    """Run the commands of ``groups``' findings as written; 1 if one does not print its findings.

    Parameters
    ----------
    committed : dict
        Name -> committed finding.
    groups : sequence of str or None
        Groups to verify (all when None).
    timeout : float or None
        Per command, seconds.
    matching : str
        Only the commands containing this text (all when empty).
    """
    from findings import commands

    results = commands.verify_all(committed, groups, timeout, report=lambda line: print(line, flush=True),
                                  matching=matching)
    print(commands.summary(results))
    return 1 if any(r.status in ("missing", "failed") for r in results) else 0


def checkout(root: Path) -> bool:
    """Whether ``root`` (the package's parent folder) is a source checkout: its ``pyproject.toml``,
    ``README.md`` and ``docs/`` beside the package, as the findings rewrite them. An installed
    copy (site-packages) has none of them."""
    return all((root / name).exists() for name in ("pyproject.toml", "README.md", "docs"))


def _check_out(path: Path, write: bool):
    """Refuse ``--out`` before any group runs: a folder, or (when it is to be written) what the one
    writer refuses (:func:`quadcosim.infra.files.output_file`: a FIFO, a device, a missing folder)."""
    from quadcosim.infra.files import OutputRefused, output_file

    if path.is_dir():
        raise OutputRefused(f"--out {path}: a folder, not a file; give a findings file such as findings.json")
    if write:
        output_file(path)


def main(argv=None) -> int:
    """Run the findings; returns the exit code (2: a bad command line, or a copy that is not a
    source checkout (:func:`checkout`: nothing is written into an installed package); 1:
    ``--check`` found a difference or checked nothing (every group skipped), or the README could
    not be rewritten).

    Parameters
    ----------
    argv : list of str, optional
        The arguments (the process's if None).
    """
    args = parser().parse_args(argv)
    unknown = [g for g in args.groups if g not in findings.GROUPS]
    if unknown:
        print(f"python -m findings: unknown group {', '.join(unknown)}; groups: {', '.join(findings.GROUPS)}",
              file=sys.stderr)
        return 2
    if not checkout(findings.ROOT):
        print(f"python -m findings: a maintainer's tool, run from a source checkout: it measures the README's "
              f"numbers into findings.json and rewrites the README and docs/ beside it. This copy of quadcosim is "
              f"installed in {findings.ROOT} (no pyproject.toml, README.md and docs/ there) and is not written "
              "into; clone the repository and run it there", file=sys.stderr)
        return 2
    try:
        _check_out(args.out, write=not (args.check or args.verify_commands))
        committed = findings.load(args.out)
    except (ValueError, OSError) as error:  # OutputRefused and FindingError among them
        print(f"python -m findings: {error}", file=sys.stderr)
        return 2
    if args.verify_commands:
        return verify_commands(committed, args.groups or None, args.timeout, args.matching)
    computed, skipped = run(args.groups or findings.GROUPS, args.quick)
    for group, reason in skipped.items():
        kept = [n for n, f in committed.items() if f["group"] == group]
        print(f"{group}: skipped ({reason}); its {len(kept)} committed values are kept", file=sys.stderr)
    if args.check:
        if not computed:
            print(f"python -m findings --check: nothing was checked: every group asked for was skipped "
                  f"({', '.join(skipped)}); give their data (see each reason above) to check them", file=sys.stderr)
            return 1
        lines = findings.differences(computed, committed)
        for line in lines:
            print(line, file=sys.stderr)
        unchecked = f"; {len(skipped)} groups skipped, not checked ({', '.join(skipped)})" if skipped else ""
        print(f"{len(computed)} findings computed, {len(lines)} differences from {args.out}{unchecked}")
        return 1 if lines else 0
    new = committed | {f["name"]: f for f in computed}
    try:
        findings.save(new, args.out)
    except OSError as error:  # a full disk (named, the earlier file kept whole) or a folder gone meanwhile
        print(f"python -m findings: {error}", file=sys.stderr)
        return 1
    print(f"{len(computed)} findings written to {args.out}")
    if args.no_readme:
        return 0
    unresolved = []
    for page in readme.pages(args.out.parent):
        unresolved += readme.rewrite(page, committed, new)
    for line in unresolved:
        print(f"not rewritten: {line}", file=sys.stderr)
    return 1 if unresolved else 0


if __name__ == "__main__":
    sys.exit(main())
