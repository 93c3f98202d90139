"""``quadcosim plot RUN SIGNAL...`` and ``quadcosim compare RUN RUN... SIGNAL``: figures of finished
runs (:mod:`quadcosim.scenarios.run_plots`)."""

from __future__ import annotations


def add(sub) -> None:
    """Add the ``plot`` and ``compare`` verbs to the sub-parsers ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``quadcosim`` parser's sub-parsers.
    """
    from quadcosim.scenarios import run_plots

    run_plots.add_arguments(sub)
