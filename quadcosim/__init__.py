"""The ``quadcosim`` command line (:mod:`quadcosim.main`), the top floor: it imports the
scenarios, the studies and the benchmarks, and nothing imports it."""
