"""In-flight calibration of an infrared horizon sensor against the GPS turn rate.

After "Calibration d'un récepteur Infra-Rouge pour Micro Drone" (Paparazzi project, 2004): the
infrared reading is linear in the turn rate for small bank angles, ``IR = a r + b``, with ``a``
and ``b`` drifting with time of day, temperature and cloud. The GPS gives a reliable but late
turn rate. Three estimators of ``(a, b)`` and of the present turn rate ``(IR - b) / a``:

- ``Estimator("kalman")`` (:class:`EKFSettings`, :func:`ekf_step`): the slides' extended Kalman
  filter on ``(a, b, r)``, measurements the GPS turn rate and the IR, random-walk model
  (``F = I``). It is written as two sequential scalar updates (``form="sequential"``, cheaper,
  the default) or as the slides' joint update (``form="joint"``, :func:`ekf_joint_step`).
  Beyond the slides: innovation gating as in PX4's EKF2 (test ratio
  ``nu^2 / (gamma^2 S)``, a rejected measurement is not fused), and CUSUM detectors on the
  normalised innovations that declare a fault, attribute it to the IR or the GPS and end it
  when that sensor is consistent again (:mod:`quadcosim.calibration.infrared.detection`). A fourth CUSUM
  watches the GPS-IR consistency residual against the calibration of a few samples before, which
  has not yet absorbed a small offset into ``b``, and a generalised likelihood ratio on the
  residual's shape (a GPS offset: a step; an IR offset: a ramp over the GPS window) names the
  sensor. The present
  IR is also checked against the state, so that an IR fault is declared before it reaches the
  paired window. While the GPS is not fused, the IR updates the turn rate only, so ``a`` and
  ``b`` keep their calibration; when a fault ends their variances are raised back to the
  initial ones.
- ``Estimator("regression")`` (:class:`RegressionSettings`, :func:`regression_step`): the
  slides' baseline, the least-squares line through all the paired samples since take-off,
  recomputed every second, unrealistic points rejected.
- ``Estimator("rls")`` (:class:`RLSSettings`, :func:`rls_step`): the recursive least squares
  with forgetting factor 0.995 of Paparazzi's flight code, updated only when the GPS bank angle
  lies in [0.05, 1] rad.

Pairing: the GPS turn rate at sample ``k`` is the heading difference over the ``window``
samples ``[k - delay - window, k - delay)``, i.e. the mean turn rate there. Every estimator is
fed the mean IR over the same samples (:func:`pair_at`), so that the pair refers to one
stretch of flight, as the slides pair IR and GPS "without offset".

Each estimator's arithmetic is one compiled step function, called by the batch path (a
compiled loop over recorded arrays, :meth:`Estimator.run`) and by the streaming block
(:class:`InfraredCalibration`, an :class:`quadcosim.orchestrator.Block`). :func:`cost` counts the
operations of each step by running the same Python source on counting numbers, and times it.

Modules, one concern each: :mod:`~quadcosim.calibration.infrared.layout` (the state vectors),
:mod:`~quadcosim.calibration.infrared.filters` (the step functions), :mod:`~quadcosim.calibration.infrared.detection`
(faults), :mod:`~quadcosim.calibration.infrared.estimator` (settings, the estimator and its block),
:mod:`~quadcosim.calibration.infrared.cost` (operations and time per iteration).

Units: turn rate rad/s, IR in counts, ``a`` in counts per rad/s.
"""

from quadcosim.calibration.infrared.cost import SLIDES_OPERATIONS, SLIDES_PROCESSOR, SLIDES_RATE, cost
from quadcosim.calibration.infrared.estimator import METHODS, Estimator, InfraredCalibration, InfraredCalibrationError
from quadcosim.calibration.infrared.settings import EKFSettings, RegressionSettings, RLSSettings

__all__ = ["METHODS", "SLIDES_OPERATIONS", "SLIDES_PROCESSOR", "SLIDES_RATE", "InfraredCalibrationError", "EKFSettings",
           "Estimator", "InfraredCalibration", "RLSSettings", "RegressionSettings", "cost"]
