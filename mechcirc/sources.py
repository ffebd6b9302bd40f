"""Reading the text files mechcirc accepts (netlists, linkages, scenes), with located errors."""

from __future__ import annotations

import os
from pathlib import Path

from .errors import NetlistError

__all__ = ["read_source"]


def read_source(path: str | os.PathLike, expected: str) -> str:
    """The UTF-8 text of ``path`` (a byte-order mark dropped).

    ``expected`` names what the file should be (e.g. ``"a .mcir netlist"``),
    for the messages.

    Raises
    ------
    NetlistError
        If the file is missing, a folder, unreadable, or not UTF-8 (then with
        the line and column of the first bad byte).
    """
    source = os.fspath(path)
    try:
        data = Path(path).read_bytes()
    except FileNotFoundError:
        raise NetlistError("no such file", source, 0, 0, f"the path of {expected}") from None
    except IsADirectoryError:
        raise NetlistError("is a directory", source, 0, 0, f"{expected} file") from None
    except OSError as exc:
        raise NetlistError(f"cannot read: {exc.strerror}", source) from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        before = data[:exc.start]
        line = before.count(b"\n") + 1
        col = exc.start - (before.rfind(b"\n") + 1) + 1
        raise NetlistError(f"byte 0x{data[exc.start]:02x} is not valid UTF-8", source,
                           line, col, "a UTF-8 text file") from None
    return text.removeprefix("\ufeff")
