"""The autopilots: each one folder of this package (or of a third party's), registered by one line in
the entry-point group ``quadcosim.autopilots`` (:mod:`quadcosim.infra.members`)::

    [project.entry-points."quadcosim.autopilots"]
    ArduPilot = "quadcosim.flightlogs.autopilots.ardupilot:AUTOPILOT"

The line's name is the autopilot's name as its logs give it (:attr:`quadcosim.flightlogs.FlightLog.autopilot`),
its value an :class:`Autopilot`. The member carries everything of its firmware: the log formats it
writes and how to tell them from a file's first bytes (:class:`LogFormat`), the messages that carry
each part of a log, the firmware arithmetic (how it applies its compass parameters, cited from its
source) and its parameter file. The log reading (:func:`quadcosim.flightlogs.read_log`), ``quadcosim
log info``, the flight calibration and its export, and the documentation's tables read the registry
(:func:`registry`); none of them names an autopilot.

The callables that take ``part`` are given one compass of one of the autopilot's logs as the
calibration aligns it (:class:`quadcosim.calibration.flight.data.FlightData`: its ``log``, ``compass``
index, ``raw`` field); ``rule`` is what ``--firmware`` named (:attr:`Autopilot.versions`), None for the
log's own firmware.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from quadcosim.infra.errors import UsageError

#: The entry-point group of the autopilots.
GROUP = "quadcosim.autopilots"
#: How many of a file's first bytes a format's detection is given.
HEAD_BYTES = 64


@dataclass(frozen=True)
class LogFormat:
    """One log format an autopilot writes.

    Attributes
    ----------
    name : str
        As :attr:`quadcosim.flightlogs.FlightLog.format` and ``log info`` name it (``dataflash-binary``).
    description : str
        For messages: what it is and its usual suffix (``ArduPilot DataFlash binary (.bin)``).
    recognises : callable
        ``(head)``: whether a file starting with the bytes ``head`` (its first :data:`HEAD_BYTES`, fewer
        in a short file) is in this format; from the content, never the file's name.
    read : callable
        ``(path)``: the log as a :class:`quadcosim.flightlogs.FlightLog` (raising
        :class:`quadcosim.flightlogs.LogError` naming the file, the defect and the fix).
    """

    name: str
    description: str
    recognises: Callable[[bytes], bool]
    read: Callable


@dataclass(frozen=True)
class Autopilot:
    """An autopilot: its logs, its firmware's compass arithmetic and its parameter file.

    Attributes
    ----------
    name : str
        As its logs name it (:attr:`quadcosim.flightlogs.FlightLog.autopilot`) and its registry line does.
    formats : tuple of LogFormat
        The log formats it writes, each detected by its first bytes.
    messages : dict
        The log's messages (or topics) carrying each part of a log, ``compass``, ``imu``, ``attitude``,
        ``motors`` and ``battery``: named when a log lacks one.
    logging : str
        The setting that chooses what it logs (``LOG_BITMASK``).
    faster_compass : str
        How to log the compass faster, when a flight calibration refuses its rate.
    file : str
        The parameter file the export writes in the results folder.
    write : callable
        ``(params, path)``: the parameters (name: value) in the autopilot's file format at ``path``.
    apply : callable
        ``(part, params, inputs, rule)``: the body-frame field (T, 3) (T) the firmware reports from the
        part's raw field with ``params`` (all of them, the log's included) and ``inputs``
        (``current`` (A), ``throttle`` (0..1), ``commands`` (0..1), ``voltage`` (V)).
    parameters : callable
        ``(part, candidate, rule)``: a fitted candidate (hard iron ``offset`` (T), soft-iron inverse
        ``correction`` (1), motor ``model`` and its field ``K`` (T per unit of the model's input)) as
        the firmware's parameters of the part's compass, name: value in the firmware's units.
    motor_models : callable
        ``(part, rule)``: the motor compensations the firmware has for the part's compass, names of
        the interference models (group ``quadcosim.interference``), richest first.
    motor_inputs : callable
        ``(model, inputs)``: the (T, J) regressors the firmware multiplies for its compensation
        ``model``, from ``inputs`` as ``apply`` takes them; None when the log lacks them.
    scale_reset : callable
        ``(part, rule)``: parameters to reset when a fitted soft iron is exported (it carries the scale).
    firmware : callable
        ``(part, rule)``: the firmware as the export's metrics name it (str).
    motor_off : dict
        The parameters that switch the firmware's motor compensation off.
    is_motor_key : callable
        ``(name)``: whether a parameter name is one of the motor compensation's.
    fused_compass : callable
        ``(params)``: the compass (0-based) the firmware's heading fuses.
    board_trim : callable or None
        ``(params)``: the rotation (3, 3) from the vehicle to the board that the logged attitude leaves
        out; None: the logged attitude is the sensors' frame's.
    enabling : callable or None
        ``(part)``: the parameters a compass the log's firmware does not use needs to be used; empty
        for a compass in use; None: the firmware has no such switch.
    versions : callable or None
        ``(text)``: the rules of the firmware version ``text`` (``--firmware``), raising ValueError
        naming what a version looks like; None: the autopilot has one set of rules, the log's.
    parameter_line : callable or None
        ``(line)``: the name and value (str, str) of one line of its parameter file (neither blank
        nor a ``#`` comment), raising ValueError or IndexError for a line that holds none, as
        ``quadcosim calibrate --score`` reads the file; None: ArduPilot's ``NAME,VALUE`` and
        QGroundControl's tab-separated lines (:func:`quadcosim.calibration.flight.autopilot.read_parameters`).
    """

    name: str
    formats: tuple[LogFormat, ...]
    messages: dict
    logging: str
    faster_compass: str
    file: str
    write: Callable[[dict, object], None]
    apply: Callable
    parameters: Callable
    motor_models: Callable
    motor_inputs: Callable
    scale_reset: Callable
    firmware: Callable
    motor_off: dict
    is_motor_key: Callable[[str], bool]
    fused_compass: Callable[[dict], int]
    board_trim: Callable | None = None
    enabling: Callable | None = None
    versions: Callable[[str], object] | None = None
    parameter_line: Callable[[str], tuple[str, str]] | None = None


class UnknownAutopilot(UsageError, KeyError):
    """A name no installed package registers as an autopilot."""

    def __str__(self) -> str:
        return str(self.args[0])


def registry() -> dict[str, Autopilot]:
    """The installed autopilots, name: :class:`Autopilot`, this package's first.

    Raises
    ------
    quadcosim.infra.members.RegistrationRefused
        A registry line names something that is not an :class:`Autopilot` of the line's own name.
    """
    from quadcosim.infra.members import loaded

    return loaded(GROUP, Autopilot)


def of(name: str) -> Autopilot:
    """The installed autopilot ``name`` (as a log names it); :class:`UnknownAutopilot` naming those installed."""
    known = registry()
    if name not in known:
        raise UnknownAutopilot(f"no installed autopilot is named {name!r}; installed: {', '.join(known)}")
    return known[name]


def formats() -> list[tuple[Autopilot, LogFormat]]:
    """Every log format of every installed autopilot, in the registry's order, with its autopilot."""
    return [(autopilot, found) for autopilot in registry().values() for found in autopilot.formats]


def known_formats() -> str:
    """The log formats read, in words, for messages (``PX4 ULog (.ulg), ArduPilot ... or ...``)."""
    named = [found.description for _, found in formats()]
    return ", ".join(named[:-1]) + (" or " if len(named) > 1 else "") + named[-1] if named else "no format"


def recognised(head: bytes) -> tuple[Autopilot, LogFormat] | None:
    """The autopilot and format whose detection claims a file starting with ``head``, or None."""
    return next(((autopilot, found) for autopilot, found in formats() if found.recognises(head)), None)
