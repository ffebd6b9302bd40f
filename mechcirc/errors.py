"""Exception and warning classes of mechcirc.

Every error a user can cause is a :class:`MechcircError`; the command line
prints it as one line and exits with status 2.  Errors tied to a place in a
file carry that place (:class:`NetlistError`).  Dual bases (``ValueError``,
``RuntimeError``) let callers catch either the mechcirc class or the builtin.
"""

from __future__ import annotations

__all__ = [
    "MechcircError",
    "NetlistError",
    "InputError",
    "TopologyError",
    "NotSeriesParallelError",
    "GeometryError",
    "SolverError",
    "MechcircWarning",
    "UnloadedElementWarning",
    "SingularPointWarning",
]


class MechcircError(Exception):
    """Base class of every error mechcirc raises on purpose."""


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
        where = self.source
        if self.line:
            where += f":{self.line}:{self.col}"
        text = f"{where}: error: {self.message}"
        if self.expected:
            text += f" (expected {self.expected})"
        return text


class InputError(MechcircError, ValueError):
    """An argument out of its domain (a non-finite ω, a negative count): the caller's mistake."""


class TopologyError(MechcircError, ValueError):
    """The network cannot be analysed as asked; names the blocking nodes/elements."""

    def __init__(self, message: str, nodes=(), elements=()):
        self.message = message
        self.nodes = tuple(nodes)
        self.elements = tuple(elements)
        super().__init__(message)


class NotSeriesParallelError(TopologyError):
    """The network (or a lever's secondary side) is not series–parallel reducible.

    Nodal analysis handles it; ``method="auto"`` falls back to it.
    """


class GeometryError(MechcircError, ValueError):
    """A linkage that cannot be assembled, locks, or is singular where asked."""


class SolverError(MechcircError, RuntimeError):
    """A numerical method failed (integration, root search); carries ``status``."""

    def __init__(self, message: str, status: int | str | None = None):
        self.status = status
        super().__init__(message)


class MechcircWarning(UserWarning):
    """Base class of mechcirc's warnings."""


class UnloadedElementWarning(MechcircWarning):
    """Elements lie on no path between the drive terminals and carry no force."""


class SingularPointWarning(MechcircWarning):
    """A sweep point falls on (or within rounding of) a pole or zero of K."""
