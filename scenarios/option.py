"""A scenario's option (:class:`Option`: its default, unit, choices and help) and the settings that
give options their values, read once (:func:`settings_pairs`)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass


@dataclass
class Option:
    default: object
    help: str
    choices: tuple | None = None
    minimum: float | None = None
    classes: bool = False  # beside the choices, a block class of the user's, "module:Class"
    files: str | None = None  # beside the choices, a file of this suffix (".csv"), read by the scenario
    applies: str | None = None  # "other=a,b": the option acts only when option `other` is a or b
    #: A word that stands for a value the scenario chooses (``kI = "lab"``: the chosen estimator's lab
    #: value); the option then takes that word or a number (float). The default is the word, shown
    #: as it is everywhere (``quadcosim list``, ``metrics.json``, the result files, ``sweep.csv``)
    #: until the scenario resolves it (:attr:`Scenario.resolve`).
    marker: str | None = None

    @property
    def unit(self) -> str | None:
        """The option's unit, the first parenthesised unit of its help (``"(s)"``), or None."""
        from quadcosim.scenarios.metrics import option_unit

        return option_unit(self.help)

    def parse(self, name: str, text):
        """The option's value from text, checked against its type, choices and minimum.

        Parameters
        ----------
        name : str
            Option name, for messages.
        text : str or value
            ``"0.5"``, ``"true"``, ...

        Returns
        -------
        object
            The value, of the default's type.

        Raises
        ------
        ValueError
            Not a valid value; the message says what is expected.
        """
        default = self.default
        if self.marker is not None:
            if str(text).strip().lower() == self.marker:
                return self.marker
            default = 0.0  # otherwise a number
        if isinstance(text, (list, tuple, dict, set)) or text is None or \
                (isinstance(text, bool) and not isinstance(default, bool)):
            also = f" (or {self.marker})" if self.marker is not None else ""
            raise ValueError(f"option {name}={text!r} is not a valid {type(default).__name__}{also}: give one "
                             f"value, such as {self.default!r}")
        try:
            if isinstance(default, bool):
                if str(text).lower() in ("1", "true", "on", "yes"):
                    value = True
                elif str(text).lower() in ("0", "false", "off", "no"):
                    value = False
                else:
                    raise ValueError(text)
            elif isinstance(default, int):
                value = int(text)
            elif isinstance(default, float):
                value = float(text)
                if not math.isfinite(value):
                    raise ValueError(text)
            else:
                value = str(text)
        except ValueError:
            also = f" (or {self.marker})" if self.marker is not None else ""
            raise ValueError(f"option {name}={text!r} is not a valid {type(default).__name__}{also}") from None
        file = self.files is not None and str(value).lower().endswith(self.files)
        if self.choices and value not in self.choices and not (self.classes and ":" in value) and not file:
            other = " or module:Class (a block of your own)" if self.classes else ""
            other += f" or a {self.files} file" if self.files else ""
            raise ValueError(f"option {name}={text!r} must be one of {', '.join(map(str, self.choices))}{other}")
        if self.minimum is not None and value < self.minimum:
            raise ValueError(f"option {name}={value} must be at least {self.minimum}")
        return value


def settings_pairs(settings: dict | list | tuple | None) -> list[tuple[str, object]]:
    """``(key, value)`` pairs of ``settings``: a mapping's items, or ``"key=value"`` texts split
    once at their first ``=`` (None: none).

    Raises
    ------
    ValueError
        A text with no ``=``; the message shows the form.
    """
    if isinstance(settings, Mapping):
        return list(settings.items())
    pairs = []
    for text in settings or []:
        key, eq, value = str(text).partition("=")
        if not eq:
            raise ValueError(f"--set {text!r}: write key=value")
        pairs.append((key.strip(), value.strip()))
    return pairs
