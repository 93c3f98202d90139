"""Studies: the sweep engine (:mod:`studies.sweep`) and the scripts that run many scenarios to
answer one question (gain studies, lab matrices, the infrared detection studies, Metge's
robustness and free-set studies, the yaw loop).

They stand above :mod:`scenarios`, whose runs they combine, and below the command line. A
study that is also a scenario (``quadcosim run gain-study``) is registered here, one line each,
in the scenarios' catalogue (:mod:`scenarios.catalogue`): importing this package makes it known.
"""

from scenarios.catalogue import register

register("gain-study", "studies.gain_study", __name__)
