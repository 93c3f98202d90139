"""``quadcosim sweep SCENARIO`` and ``quadcosim sweep-plot DIR METRIC``: a scenario over a grid of
options and seeds on Dask, and a metric of its table against an option
(:mod:`quadcosim.studies.sweep.command`, shared with ``python -m quadcosim.studies.sweep``)."""

from __future__ import annotations


def add(sub) -> None:
    """Add the ``sweep`` and ``sweep-plot`` verbs to the sub-parsers ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``quadcosim`` parser's sub-parsers.
    """
    from quadcosim.studies.sweep import command as sweep

    sweep.add_arguments(sub.add_parser("sweep", help="run a scenario over a grid of options and seeds, on Dask"))\
        .set_defaults(func=sweep.sweep)
    sweep.add_plot_arguments(sub.add_parser("sweep-plot", help="a metric of a sweep table against an option"))\
        .set_defaults(func=sweep.sweep_plot)
