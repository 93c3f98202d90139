"""``python -m quadcosim.main``: the ``quadcosim`` command line (:mod:`quadcosim.cli`), under the
name it has always had; :func:`main`, :func:`entry` and :func:`parser` are the package's."""

from __future__ import annotations

from quadcosim.cli import entry, main, parser

__all__ = ["entry", "main", "parser"]

if __name__ == "__main__":
    entry()
