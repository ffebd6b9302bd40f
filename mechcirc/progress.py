"""A progress bar on stderr, only for a terminal and only for work that lasts.

Nothing is drawn when the stream is not a terminal (pipes, files, CI logs)
or before ``delay`` seconds have passed, so short runs and scripted runs stay
silent.  No third-party package: one line redrawn with a carriage return.
"""

from __future__ import annotations

import sys
import time

__all__ = ["Progress"]


class Progress:
    """Count ``total`` steps; draw ``label [#####.....] done/total  rate  eta`` when it is worth it.

    Use as a context manager; :meth:`update` adds finished steps, or pass the bar
    itself as a ``progress(done, total)`` callback (the total may be unknown at
    construction: ``Progress(0, label)``).
    """

    def __init__(self, total: int, label: str = "", *, stream=None, delay: float = 1.0,
                 width: int = 30, enabled: bool | None = None):
        self.total, self.label, self.width, self.delay = max(int(total), 0), label, width, delay
        self.stream = stream if stream is not None else sys.stderr
        if enabled is None:
            isatty = getattr(self.stream, "isatty", None)
            enabled = bool(isatty and isatty())
        self.enabled = enabled
        self.done = 0
        self.start = time.monotonic()
        self._last = 0.0
        self._drawn = False

    def update(self, n: int = 1) -> None:
        """Record ``n`` more finished steps and redraw at most ten times a second."""
        self.done += n
        if not self.enabled:
            return
        now = time.monotonic()
        if now - self.start < self.delay or (now - self._last < 0.1 and self.done < self.total):
            return
        self._last = now
        self._draw(now)

    def __call__(self, done: int, total: int) -> None:
        """Set the total and the finished count, for APIs that report ``progress(done, total)``.

        Parameters
        ----------
        done : int
            Steps finished so far.
        total : int
            Steps in all.
        """
        self.total = max(int(total), 0)
        self.update(done - self.done)

    def _draw(self, now: float) -> None:
        frac = self.done / self.total if self.total else 1.0
        filled, elapsed = int(round(frac * self.width)), now - self.start
        rate = self.done / elapsed if elapsed > 0 else 0.0
        eta = (self.total - self.done) / rate if rate > 0 else float("inf")
        eta_text = f"{eta:5.0f} s left" if eta != float("inf") else "      "
        self.stream.write(f"\r{self.label} [{'#' * filled}{'.' * (self.width - filled)}] "
                          f"{self.done}/{self.total} {rate:7.1f}/s {eta_text}")
        self.stream.flush()
        self._drawn = True

    def __enter__(self) -> "Progress":
        return self

    def __exit__(self, *exc) -> None:
        if self._drawn:
            self._draw(time.monotonic())
            self.stream.write("\n")
            self.stream.flush()
