"""Real flight logs on the command line: ``quadcosim log info|plot FILE`` and
``quadcosim calibrate FILE... --compass N --out DIR`` (reading in :mod:`flightlogs`,
the fits in :mod:`quadcosim.calibration.flight`)."""
