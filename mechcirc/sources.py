"""Reading the text files mechcirc accepts (netlists, linkages, scenes), with located errors."""

from __future__ import annotations

import os
import stat

from .errors import NetlistError

__all__ = ["read_source", "read_bytes", "MAX_INPUT_BYTES"]

#: The largest input file mechcirc reads [bytes].  A netlist of the statement
#: limit is far below this; anything larger is refused before it is read.
MAX_INPUT_BYTES = 64 * 2**20


def read_bytes(path: str | os.PathLike, expected: str) -> bytes:
    """The bytes of the regular file ``path``, at most :data:`MAX_INPUT_BYTES`.

    Devices, pipes and sockets (``/dev/zero``, a FIFO) are refused before
    anything is read, and so is a file larger than the bound; at most
    ``MAX_INPUT_BYTES + 1`` bytes are ever read, so a file that grows while
    it is read cannot exhaust memory either.

    Raises
    ------
    NetlistError
        If the file is missing, a folder, not a regular file, unreadable or
        too large.
    """
    source = os.fspath(path)
    try:
        info = os.stat(source)
    except FileNotFoundError:
        raise NetlistError("no such file", source, 0, 0, f"the path of {expected}") from None
    except OSError as exc:
        raise NetlistError(f"cannot read: {exc.strerror}", source) from None
    if stat.S_ISDIR(info.st_mode):
        raise NetlistError("is a directory", source, 0, 0, f"{expected} file") from None
    if not stat.S_ISREG(info.st_mode):
        raise NetlistError("is not a regular file (a device, pipe or socket); nothing was read",
                           source, 0, 0, f"{expected} file")
    if info.st_size > MAX_INPUT_BYTES:
        raise NetlistError(f"is {info.st_size:,} bytes, more than the limit of "
                           f"{MAX_INPUT_BYTES:,} bytes; nothing was read", source, 0, 0,
                           f"{expected} file")
    try:
        with open(source, "rb") as fh:
            data = fh.read(MAX_INPUT_BYTES + 1)
    except OSError as exc:
        raise NetlistError(f"cannot read: {exc.strerror}", source) from None
    if len(data) > MAX_INPUT_BYTES:
        raise NetlistError(f"grew past the limit of {MAX_INPUT_BYTES:,} bytes while it was "
                           "read", source, 0, 0, f"{expected} file")
    return data


def read_source(path: str | os.PathLike, expected: str) -> str:
    """The UTF-8 text of ``path`` (a byte-order mark dropped).

    ``expected`` names what the file should be (e.g. ``"a .mcir netlist"``),
    for the messages.

    Raises
    ------
    NetlistError
        If the file is missing, a folder, not a regular file, larger than
        :data:`MAX_INPUT_BYTES`, unreadable, or not UTF-8 (then with the line
        and column of the first bad byte).
    """
    source = os.fspath(path)
    data = read_bytes(path, expected)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        before = data[:exc.start]
        line = before.count(b"\n") + 1
        col = exc.start - (before.rfind(b"\n") + 1) + 1
        raise NetlistError(f"byte 0x{data[exc.start]:02x} is not valid UTF-8", source,
                           line, col, "a UTF-8 text file") from None
    return text.removeprefix("\ufeff")
