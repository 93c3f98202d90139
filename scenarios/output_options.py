"""One meaning of ``--json`` and ``--out`` across the ``quadcosim`` sub-commands.

- ``--json`` is a flag: print the result as JSON on standard output, in place of the text
  (``log info --json``, ``log replay --json``, ``bench --json``).
- ``--out PATH`` is where a command writes its files (a folder, or the one file it writes), and
  every command that writes files has a default under ``results/`` (``run``:
  ``results/SCENARIO``; ``calibrate``: ``results/calibrate-FLIGHT``; ``compare``:
  ``results/compare-SIGNAL.png``; ``log plot``: ``results/logs/``; ``plot``: the run's folder),
  never replaced unasked: a default file taken takes the next free ``-N`` name
  (:func:`free_file`), a default folder the next free ``-N`` folder (:func:`default_folder`).

The old spelling ``--json FILE`` (``log replay``, ``python -m quadcosim.scenarios.replay``) still works: it
means ``--out FILE`` and says so on standard error.
"""

from __future__ import annotations

import argparse
import sys


class JsonFlag(argparse.Action):
    """``--json``: a flag (``True``); ``--json FILE``, the old spelling, sets ``out`` to ``FILE``
    instead, with a deprecation message on standard error.

    Parameters
    ----------
    option_strings, dest
        As argparse gives them to every action.
    out_dest : str
        The attribute ``--json FILE`` sets (that of ``--out``).
    """

    def __init__(self, option_strings, dest, out_dest: str = "out", **kwargs):
        self.out_dest = out_dest
        super().__init__(option_strings, dest, nargs="?", const=True, default=False, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        if values is True:
            setattr(namespace, self.dest, True)
            return
        print(f"{parser.prog}: warning: --json FILE is deprecated: --json now prints JSON on standard output; "
              f"write the file with --out {values}", file=sys.stderr)
        setattr(namespace, self.out_dest, values)


def add_json_flag(parser, help_text: str, out_dest: str = "out"):
    """Add ``--json`` (:class:`JsonFlag`) to ``parser``, described by ``help_text``; ``out_dest``:
    the attribute ``--json FILE`` (the old spelling) sets."""
    parser.add_argument("--json", action=JsonFlag, out_dest=out_dest, metavar="",
                        help=help_text + " (--json FILE, the old spelling, is --out FILE)")


def default_folder(command: str, name: str, overwrite: bool):
    """``results/NAME``, or with earlier results there (and no ``overwrite``) the next free
    ``results/NAME-N``, said on standard error, as ``quadcosim run`` does.

    Parameters
    ----------
    command : str
        The sub-command, named in the message (``calibrate``).
    name : str
        The folder's name under ``results/``.
    overwrite : bool
        ``--overwrite`` given: the folder itself, its results to be replaced.

    Returns
    -------
    pathlib.Path
    """
    from pathlib import Path

    from quadcosim.infra.files import free_folder, holds_results

    base = Path("results") / name
    if overwrite:
        return base
    out = free_folder(base)
    if out != base:
        print(f"quadcosim {command}: {base}/ holds earlier results ({', '.join(holds_results(base))}); writing to "
              f"{out}/ (--out DIR chooses the folder, --overwrite replaces {base}/)", file=sys.stderr)
    return out


def free_file(path, command: str):
    """``path`` if no file is there, else the first free ``STEM-2.SUFFIX``, ``STEM-3.SUFFIX``, ...,
    said on standard error: a command's default figure never replaces an earlier one.

    Parameters
    ----------
    path : str or pathlib.Path
        The default file.
    command : str
        The sub-command, named in the message (``compare``, ``log plot``).

    Returns
    -------
    pathlib.Path
    """
    from pathlib import Path

    from quadcosim.infra.files import first_free

    path = Path(path)
    candidate = first_free(path, Path.exists, file=True)
    if candidate != path:
        print(f"quadcosim {command}: {path} is there; writing {candidate} (--out FILE chooses the file, --overwrite "
              f"replaces {path})", file=sys.stderr)
    return candidate
