"""``quadcosim tune SCENARIO --minimize METRIC --over NAME=LOW:HIGH``: the options that minimise a
metric, on Dask (:mod:`quadcosim.studies.tune`)."""

from __future__ import annotations


def add(sub) -> None:
    """Add the ``tune`` verb to the sub-parsers ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``quadcosim`` parser's sub-parsers.
    """
    from quadcosim.studies import tune

    tune.add_arguments(sub.add_parser("tune", help="the options that minimise a metric (scipy.optimize), on Dask"))\
        .set_defaults(func=tune.command)
