"""The README's findings: every number it states, measured by code (one module per group)."""
