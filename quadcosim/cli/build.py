"""``quadcosim build``: the plant FMUs, the master's call runner, the benchmark's C references and
the numba steps, each built when not up to date."""

from __future__ import annotations

from pathlib import Path


def add(sub) -> None:
    """Add the ``build`` verb to the sub-parsers ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``quadcosim`` parser's sub-parsers.
    """
    build = sub.add_parser("build", help="build the plant FMUs, the master's C runner and the benchmark's C "
                           "references (into build/ in a source checkout, a per-user cache when installed; a run "
                           "builds what it needs on first use)")
    build.add_argument("--out", default=None, help="output folder of the FMUs (default: fmus/ in the build folder)")
    build.add_argument("--force", action="store_true", help="rebuild the FMUs that are up to date too")
    build.set_defaults(func=command)


def command(args) -> int:
    """Build what is not up to date; raises the build's error (a compiler that refused, a folder
    that cannot be written).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed ``build`` arguments.
    """
    from quadcosim.fmus import default_fmu_dir
    from quadcosim.fmus.build import build_all
    from quadcosim.orchestrator.calls import LIBRARY_NAME, SOURCE, build_runner, runner_dir

    build_all(Path(args.out or default_fmu_dir()), force=args.force)
    library = runner_dir() / LIBRARY_NAME
    if args.force or not library.is_file() or library.stat().st_mtime < SOURCE.stat().st_mtime:
        print(f"built {build_runner()}")
    else:
        print(f"up to date {library}")
    from quadcosim.orchestrator.fmi_types import typed_path

    print(f"ready {typed_path(build=args.force)}")
    from quadcosim.benchmarks import build_references

    for library in build_references():
        print(f"built {library}")
    from quadcosim.scenarios import compiled

    seconds = compiled.compile_all()
    print(f"{'compiled' if compiled.compiled_any() else 'loaded'} the numba steps in {seconds:.1f} s")
    return 0
