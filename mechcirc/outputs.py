"""Safe output files: write to a temporary file beside the target, then rename.

An interrupted or failed write leaves either the old file or none, never a
half-written one (``os.replace`` is atomic on POSIX and Windows).

What is replaced is always a regular file (:func:`output_target`):

* a symbolic link is followed: its target is replaced, the link stays
  (a dangling link creates its target, as a shell's ``>`` does);
* a FIFO or a character device (``/dev/null``, ``/dev/stdout``, a named pipe)
  is written in place, as a stream, never replaced by a file;
* a block device, socket or folder is refused.

Errors name the output as the caller gave it, never the temporary file.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from pathlib import Path

from .errors import InputError

__all__ = ["atomic_path", "atomic_open", "OutputSet", "output_target"]


#: Names of an open file descriptor (``-o /dev/stdout``): written in place when they
#: lead to a pipe or terminal; refused when they lead to a regular file (replacing it
#: would lose what else the descriptor receives, writing into it would mix the two).
_DESCRIPTORS = ("/dev/stdout", "/dev/stderr", "/dev/fd/", "/proc/self/fd/")


def output_target(path: str | os.PathLike) -> tuple[Path, bool]:
    """The file that writing ``path`` changes, and whether it is a stream written in place.

    Parameters
    ----------
    path : str or PathLike

    Returns
    -------
    target : Path
        ``path`` with every symbolic link followed (the file that is replaced);
        ``path`` itself for a stream (opened through its links).
    stream : bool
        True for a FIFO or character device (also ``/dev/stdout`` to a pipe or
        terminal): written in place, not replaced.

    Raises
    ------
    InputError
        ``path`` is a folder, a block device or a socket, its folder (or that of
        a link's target) does not exist, its links loop, or it names a file
        descriptor open on a regular file.
    """
    given = os.fspath(path)
    target = Path(os.path.realpath(given))
    linked = target != Path(os.path.abspath(given))
    via = f"{given}: a symbolic link to {target}, which" if linked else f"{given}:"
    try:
        # The kernel follows the links: also /dev/stdout → /proc/self/fd/1 → "pipe:[…]",
        # which has no path realpath could give.
        mode = os.stat(given).st_mode
    except FileNotFoundError:
        if target.parent.is_dir():
            return target, False
        if linked:
            raise InputError(f"{given}: a symbolic link to {target}, whose folder "
                             f"{target.parent} does not exist") from None
        raise InputError(f"{given}: folder '{Path(given).parent}' does not exist") from None
    except OSError as exc:       # a link loop (ELOOP), a file used as a folder (ENOTDIR)
        raise InputError(f"{given}: cannot be written: {exc.strerror}") from None
    if stat.S_ISFIFO(mode) or stat.S_ISCHR(mode):
        return Path(given), True
    if stat.S_ISREG(mode) and os.path.abspath(given).startswith(_DESCRIPTORS):
        raise InputError(f"{given}: an open file descriptor, here of the file {target}; "
                         "give that file's name instead (through the descriptor the output "
                         "would be mixed with what else it receives)")
    if stat.S_ISREG(mode):
        return target, False
    if stat.S_ISDIR(mode):
        raise InputError(f"{via} is a folder; give a file name for the output")
    kind = "a block device" if stat.S_ISBLK(mode) else \
        "a socket" if stat.S_ISSOCK(mode) else "not a regular file"
    raise InputError(f"{via} is {kind}; an output must be a regular file (or a FIFO or "
                     "character device, written in place)")


@contextlib.contextmanager
def _naming(target: Path, given):
    """Re-raise an OSError of the temporary file or the rename as one naming ``given``."""
    try:
        yield
    except OSError as exc:
        if exc.errno is None:
            raise
        raise type(exc)(exc.errno, f"{exc.strerror} (writing into folder {target.parent})",
                        os.fspath(given)) from None


def _temporary_beside(target: Path, given) -> str:
    """Create an empty temporary file next to ``target`` (a real path from
    :func:`output_target`, absolute), with the suffix kept; errors name ``given``.

    ``mkstemp`` makes it mode 0600; it gets the mode a newly created file
    would have (0666 less the umask), since it becomes the output itself.
    """
    with _naming(target, given):
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=f".tmp{target.suffix}",
                                   dir=target.parent)
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    return tmp


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike):
    """Yield a temporary path in the target's folder; rename it to ``path`` on success.

    The temporary name keeps the target's suffix, so tools that pick a format
    from the extension (matplotlib's ``savefig``) still work.  On any exception
    (``KeyboardInterrupt`` included) the temporary file is removed.  A symbolic
    link is followed; a FIFO or character device is yielded itself, to be
    written in place (:func:`output_target`).

    Parameters
    ----------
    path : str or PathLike

    Yields
    ------
    Path
        The temporary file (or the stream) to write.
    """
    with OutputSet() as out:                # a set of one
        yield out.path(path)


@contextlib.contextmanager
def atomic_open(path: str | os.PathLike, mode: str = "w", **kwargs):
    """Open a temporary file for writing; it replaces ``path`` when the block ends cleanly.

    Parameters
    ----------
    path : str or PathLike
    mode : str
        A write mode of :func:`open`.
    **kwargs
        Further arguments of :func:`open`.

    Yields
    ------
    file object
    """
    with atomic_path(path) as tmp, open(tmp, mode, **kwargs) as fh:
        yield fh
        fh.flush()
        if stat.S_ISREG(os.fstat(fh.fileno()).st_mode):    # a FIFO cannot be synced
            os.fsync(fh.fileno())


class OutputSet:
    """Several output files that appear together or not at all.

    Use as a context manager; :meth:`path` gives a temporary path for each
    target.  When the block ends cleanly every temporary file is renamed into
    place; on any exception all of them are removed and no target changes.
    """

    def __init__(self):
        self._pending: list[tuple[Path, Path, str | os.PathLike]] = []

    def path(self, target: str | os.PathLike) -> Path:
        """A temporary path beside ``target`` (same suffix) to write it to.

        A FIFO or character device is returned itself, written in place and
        outside the all-or-nothing promise (:func:`output_target`).
        """
        given = target
        target, stream = output_target(given)
        if stream:
            return target
        tmp = _temporary_beside(target, given)
        self._pending.append((Path(tmp), target, given))
        return Path(tmp)

    def __enter__(self) -> "OutputSet":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        try:
            if exc_type is None:
                for tmp, target, given in self._pending:
                    with _naming(target, given):
                        os.replace(tmp, target)
        finally:
            # Whatever was not renamed (an error, or a rename that failed) goes.
            for tmp, _, _ in self._pending:
                with contextlib.suppress(OSError):
                    os.unlink(tmp)
            self._pending.clear()
