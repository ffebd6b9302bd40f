"""Safe output files: write to a temporary file beside the target, then rename.

An interrupted or failed write leaves either the old file or none, never a
half-written one (``os.replace`` is atomic on POSIX and Windows).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

__all__ = ["atomic_path", "atomic_open", "OutputSet"]


def _temporary_beside(target: Path) -> str:
    """Create an empty temporary file next to ``target``, with the suffix kept.

    ``mkstemp`` makes it mode 0600; it gets the mode a newly created file
    would have (0666 less the umask), since it becomes the output itself.
    """
    folder = target.parent if str(target.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=f".tmp{target.suffix}",
                               dir=folder)
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
    (``KeyboardInterrupt`` included) the temporary file is removed.
    """
    tmp = _temporary_beside(Path(path))
    try:
        yield Path(tmp)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


@contextlib.contextmanager
def atomic_open(path: str | os.PathLike, mode: str = "w", **kwargs):
    """Open a temporary file for writing; it replaces ``path`` when the block ends cleanly."""
    with atomic_path(path) as tmp:
        with open(tmp, mode, **kwargs) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())


class OutputSet:
    """Several output files that appear together or not at all.

    Use as a context manager; :meth:`path` gives a temporary path for each
    target.  When the block ends cleanly every temporary file is renamed into
    place; on any exception all of them are removed and no target changes.
    """

    def __init__(self):
        self._pending: list[tuple[Path, Path]] = []

    def path(self, target: str | os.PathLike) -> Path:
        """A temporary path beside ``target`` (same suffix) to write it to."""
        target = Path(target)
        tmp = _temporary_beside(target)
        self._pending.append((Path(tmp), target))
        return Path(tmp)

    def __enter__(self) -> "OutputSet":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        try:
            if exc_type is None:
                for tmp, target in self._pending:
                    os.replace(tmp, target)
        finally:
            # Whatever was not renamed (an error, or a rename that failed) goes.
            for tmp, _ in self._pending:
                with contextlib.suppress(OSError):
                    os.unlink(tmp)
            self._pending.clear()
