"""Numbers as the command line prints them: at the precision they carry, not as 17-digit floats
(``metrics.json`` keeps every digit)."""

from __future__ import annotations

import argparse
import math
import numbers
import re

#: Significant digits of a measured figure on the screen (a metric, a rate, an error): five, so
#: that a run prints every figure the README quotes from it at the README's precision (the tilt
#: in a steady wind, 4.1179 deg, matches its trim prediction to the fourth decimal).
MEASURED_DIGITS = 5
#: Significant digits of a parameter: enough for any value written by hand (7920, 1.19e-4,
#: 0.028), few enough to drop the last bit of a product (7920.000000000001).
PARAMETER_DIGITS = 12


def shown(value, digits: int = MEASURED_DIGITS) -> str:
    """``value`` as text, each real number at ``digits`` significant digits.

    Parameters
    ----------
    value : object
        A number, a bool, None, a string, or a list, tuple or dict of them.
    digits : int
        Significant digits of each real number.

    Returns
    -------
    str
        ``0.048064`` for 0.04806407807056596, ``[0.048064, 0.060782]`` for a list, ``7920`` for
        7920.000000000001 at 12 digits; integers, bools and text as they are.
    """
    if isinstance(value, bool) or value is None or isinstance(value, numbers.Integral):
        return str(value)
    if isinstance(value, numbers.Real):
        return f"{value:.{digits}g}" if math.isfinite(value) else str(float(value))
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {shown(v, digits)}" for k, v in value.items()) + "}"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(shown(v, digits) for v in value) + "]"
    return str(value)


_ROLE = re.compile(r":(?:data|mod|func|class|meth|attr|obj|ref|doc):`~?([^`<]*?)(?:\s*<[^>]*>)?`")
_LITERAL = re.compile(r"``([^`]+)``")


def plain(text: str) -> str:
    """reST of a docstring as plain text for a terminal: ``\\`\\`x\\`\\``` -> ``x``,
    ``:data:\\`findings.GROUPS\\``` -> ``findings.GROUPS``.

    Parameters
    ----------
    text : str
        Text with reST inline markup.

    Returns
    -------
    str
        The text without it.
    """
    return _LITERAL.sub(r"\1", _ROLE.sub(r"\1", text))


class PlainHelp(argparse.RawDescriptionHelpFormatter):
    """An argparse formatter that prints the description as written (its line breaks kept) and
    the whole help without reST markup (:func:`plain`).

    Parameters
    ----------
    prog : str
        The program's name, as argparse gives it.
    indent_increment, max_help_position, width : int, optional
        argparse's layout settings (characters).
    """

    def format_help(self) -> str:
        """The help text, plain (:func:`plain`)."""
        return plain(super().format_help())
