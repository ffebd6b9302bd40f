"""Exception and warning classes of mechcirc.

Every error a user can cause is a :class:`MechcircError`; the command line
prints it as one line and exits with status 2.  Errors tied to a place in a
file carry that place (:class:`NetlistError`).  Dual bases (``ValueError``,
``RuntimeError``) let callers catch either the mechcirc class or the builtin.
"""

from __future__ import annotations

import re

__all__ = [
    "MechcircError",
    "NetlistError",
    "InputError",
    "UnitError",
    "BandError",
    "ParameterError",
    "UnknownNameError",
    "TopologyError",
    "NotSeriesParallelError",
    "GeometryError",
    "OutOfReach",
    "SolverError",
    "MechcircWarning",
    "UnloadedElementWarning",
    "UnitMixWarning",
    "SceneAccuracyWarning",
    "SleyAccuracyWarning",
    "ShaftWarning",
    "FollowerFlightWarning",
    "PeakAccuracyWarning",
    "MAX_QUOTED",
    "clip",
    "shorten",
    "did_you_mean",
    "unknown_name",
]


#: The most characters of one piece of user text (a token, a value, a name) an
#: error message quotes; a longer one is cut and its length said.
MAX_QUOTED = 100
#: The most characters of a whole error message.
MAX_MESSAGE = 1000
# A quoted piece as repr() writes it: an opening quote not glued to a word
# (so "the drive's" is prose), escapes inside, the same quote closing it.
_QUOTED = re.compile(r"""(?<!\w)(['"])((?:\\.|(?!\1)[^\\\n])*)\1(?!\w)""")


def clip(text: str, limit: int = MAX_QUOTED) -> str:
    """``text`` cut to about ``limit`` characters, ending ``… (N characters)`` when cut.

    Parameters
    ----------
    text : str
    limit : int

    Returns
    -------
    str
    """
    if len(text) <= limit:
        return text
    return f"{text[:max(limit - 25, 10)]}… ({len(text):,} characters)"


def shorten(message: str) -> str:
    """``message`` with every quoted piece of user text longer than :data:`MAX_QUOTED`
    cut to its first 50 and last 25 characters and its length, and the whole at most
    :data:`MAX_MESSAGE` characters: an error line stays a line.

    Parameters
    ----------
    message : str

    Returns
    -------
    str
    """
    if len(message) <= MAX_QUOTED:
        return message

    def cut(m: re.Match) -> str:
        q, inner = m.group(1), m.group(2)
        if len(inner) <= MAX_QUOTED:
            return m.group(0)
        # The head and the tail: a token's start, a path's file name.
        return f"{q}{inner[:50]}…{inner[-25:]}{q} ({len(inner):,} characters)"

    return clip(_QUOTED.sub(cut, message), MAX_MESSAGE)


class MechcircError(Exception):
    """Base class of every error mechcirc raises on purpose.

    Its text quotes at most :data:`MAX_QUOTED` characters of any piece of user
    text (:func:`shorten`).
    """

    def __str__(self) -> str:
        return shorten(super().__str__())


class NetlistError(MechcircError, ValueError):
    """A problem in an input file, located by file, line and column.

    Parameters
    ----------
    message : str
        What is wrong, naming the offending thing and its value.
    source : str
        File name (or ``"<string>"``).
    line, col : int
        1-based line and column; 0 when the whole file is to blame.
    expected : str, optional
        What would have been right.
    """

    def __init__(self, message: str, source: str = "<string>", line: int = 0,
                 col: int = 0, expected: str | None = None):
        self.message = message
        self.source = source
        self.line = line
        self.col = col
        self.expected = expected
        super().__init__(str(self))

    def __str__(self) -> str:
        where = clip(self.source, 2 * MAX_QUOTED)     # a path typed on the command line
        if self.line:
            where += f":{self.line}:{self.col}"
        text = f"{where}: error: {self.message}"
        if self.expected:
            text += f" (expected {self.expected})"
        return shorten(text)


class InputError(MechcircError, ValueError):
    """An argument out of its domain (a non-finite ω, a negative count): the caller's mistake."""


class UnitError(MechcircError, ValueError):
    """A unit that cannot be parsed; ``offset`` is the 0-based position of the culprit.

    The readers turn it into a :class:`NetlistError` at the unit's line and column.
    """

    def __init__(self, message: str, offset: int, expected: str | None = None):
        self.message, self.offset, self.expected = message, offset, expected
        super().__init__(message)


class BandError(MechcircError, ValueError):
    """A frequency band or tolerance that cannot be used (names the values)."""


class ParameterError(MechcircError, ValueError):
    """A sley parameter is out of range (names the parameter, its value, what is allowed),
    or an unknown preset, method or option."""


class UnknownNameError(MechcircError, KeyError):
    """A name looked up that is not there (a node, an element, a crank, a column): the message
    names the nearest and those there are (:func:`unknown_name`).  A ``KeyError`` too, as a
    dictionary's look-up is, so ``except KeyError`` still catches it."""

    def __str__(self) -> str:
        # KeyError's str() is the repr of its key: the message would print in quotes.
        return shorten(str(self.args[0])) if self.args else ""


def unknown_name(name, names, what: str = "element", where: str = "") -> UnknownNameError:
    """The error for ``name`` not among ``names``: "no node named 'Mm'[ where]; did you mean
    'M'? (nodes: ...)" (``what`` the kind of name; at most 20 listed).

    Parameters
    ----------
    name : object
        The name asked for.
    names : iterable of str
        The names there are.
    what, where : str
        The kind of name, and where it was looked for (" on a path of the drive").

    Returns
    -------
    UnknownNameError
        To raise.
    """
    names = sorted(map(str, names))
    listed = ", ".join(names[:20]) + (f", … ({len(names)} in all)" if len(names) > 20 else "")
    return UnknownNameError(f"no {what} named {name!r}{where}{did_you_mean(str(name), names)} "
                            f"({what}s: {listed or 'none'})")


def did_you_mean(word: str, choices) -> str:
    """``"; did you mean 'x'?"`` for the nearest of ``choices`` (difflib), or ``""``.

    A choice that differs only in case comes first (``b`` → ``B``), then one
    that differs only in its separators or in writing ω as ``w``
    (``--wmax`` → ``--omega-max``, ``omega_max`` → ``omega-max``), then the
    nearest by difflib's ratio (an option's leading dashes left out), then one that
    begins ``word`` or that ``word`` begins (``maximum`` → ``max``).

    Parameters
    ----------
    word : str
        The unknown word.
    choices : iterable of str
        The words it could have been.

    Returns
    -------
    str
    """
    import difflib

    choices, word = [str(c) for c in choices], str(word)[:100]
    # an option's leading dashes, which every option shares, do not make two alike
    # ('--node' is not near '--debug')
    bare = {c.lstrip("-"): c for c in reversed(choices)}
    close = [c for c in choices if c.lower() == word.lower()] or \
        [c for c in choices if _spelling(c) == _spelling(word)] or \
        [bare[c] for c in difflib.get_close_matches(word.lstrip("-"), list(bare), n=1)] or \
        [c for c in choices if len(c) >= 3 and len(word) >= 3
         and (c.startswith(word) or word.startswith(c))][:1]
    return f"; did you mean {close[0]!r}?" if close else ""


def _spelling(word: str) -> str:
    """``word`` without case, ``-`` or ``_``, with ``omega`` written ``w``."""
    return re.sub(r"[-_]", "", word.lower()).replace("omega", "w")


class TopologyError(MechcircError, ValueError):
    """The network cannot be analysed as asked; names the blocking nodes/elements.

    ``location`` is ``FILE:LINE:COL`` of the statement at fault, when known (the CLI
    shows it).
    """

    def __init__(self, message: str, nodes=(), elements=(), location: str | None = None):
        self.message = message
        self.nodes = tuple(nodes)
        self.elements = tuple(elements)
        self.location = location
        super().__init__(message)


class NotSeriesParallelError(TopologyError):
    """The network (or a lever's secondary side) is not series–parallel reducible.

    Nodal analysis handles it; ``method="auto"`` falls back to it.
    """


class GeometryError(MechcircError, ValueError):
    """A linkage that cannot be assembled, locks, or is singular where asked."""


class OutOfReach(GeometryError):
    """A crank angle farther from the pose than the continuation's step limit goes
    (``linkage.MAX_CONTINUATION_STEPS``); the linkage itself may be fine there."""


class SolverError(MechcircError, RuntimeError):
    """A numerical method failed (integration, root search); carries ``status``."""

    def __init__(self, message: str, status: int | str | None = None):
        self.status = status
        super().__init__(message)


class MechcircWarning(UserWarning):
    """Base class of mechcirc's warnings."""


class UnloadedElementWarning(MechcircWarning):
    """Elements lie on no path between the drive terminals and carry no force."""


class UnitMixWarning(MechcircWarning):
    """A node carries both translational and rotational quantities (kg with kg·m², N/m with
    N·m/rad): one node is one coordinate, a length or an angle, not both."""


class SceneAccuracyWarning(MechcircWarning):
    """A time-domain result may be inaccurate (the message says which check failed)."""


class FollowerFlightWarning(MechcircWarning):
    """A cam follower flew across the whole gap of its contact model (the motion past it is
    not a free flight)."""


class ShaftWarning(MechcircWarning):
    """A dynamic main shaft's motor cannot give the peak load torque (the flywheel carries it)."""


class PeakAccuracyWarning(MechcircWarning):
    """A peak was searched around the sweep's grid only (the circuit's resonances could not
    be found): a narrow peak between two grid points may be missed (:attr:`Peak.note`)."""


class SleyAccuracyWarning(MechcircWarning):
    """A sley result may be inaccurate (error estimate, periodicity or too few steps)."""


def warn(message: str, category: type[Warning]) -> None:
    """Issue a warning attributed to the caller's line: the first frame outside mechcirc.

    A fixed ``stacklevel`` names the right line only for one call path; the
    analysis methods, cached properties and functions reach the same warning
    at different depths.
    """
    import functools
    import os
    import sys
    import types
    import warnings

    inside = (os.path.dirname(os.path.abspath(__file__)) + os.sep, functools.__file__)
    frame: types.FrameType | None = sys._getframe(1)
    level = 2
    while frame is not None and frame.f_code.co_filename.startswith(inside):
        frame, level = frame.f_back, level + 1
    warnings.warn(message, category, stacklevel=level)
