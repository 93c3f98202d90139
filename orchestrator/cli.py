"""The ``quadcosim`` command line."""

from __future__ import annotations

import argparse
import sys


def _build(args) -> int:
    from fmus.build import BuildError, build_all

    try:
        build_all(args.out)
    except BuildError as error:
        print(error, file=sys.stderr)
        return 1
    return 0


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="quadcosim", description=__doc__)
    sub = p.add_subparsers(dest="command", required=True)
    build = sub.add_parser("build", help="build the plant FMUs from source into build/fmus")
    build.add_argument("--out", default=None, help="output folder (default build/fmus)")
    build.set_defaults(func=_build)
    return p


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
