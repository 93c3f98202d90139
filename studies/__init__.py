"""Studies: the sweep engine (:mod:`quadcosim.studies.sweep`) and the scripts that run many scenarios to
answer one question (gain studies, lab matrices, the infrared detection studies, Metge's
robustness and free-set studies, the yaw loop).

They stand above :mod:`quadcosim.scenarios`, whose runs they combine, and below the command line.
A study that is also a scenario (``quadcosim run gain-study``) is registered as every scenario is,
by a line of the entry-point group ``quadcosim.scenarios`` in ``pyproject.toml``.
"""
