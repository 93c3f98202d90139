"""Studies: the sweep engine (:mod:`studies.sweep`) and the scripts that run many scenarios to
answer one question (gain studies, lab matrices, the infrared detection studies, Metge's
robustness and free-set studies, the yaw loop).

They stand above :mod:`scenarios`, whose runs they combine, and below the command line.
"""
