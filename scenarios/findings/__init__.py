"""Findings: the measured numbers the README prints, one module per group, each with ``compute``."""
