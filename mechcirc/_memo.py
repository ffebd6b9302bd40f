"""Memos on plain data: values derived from a frozen dataclass's own fields and kept on
it (a :func:`functools.cached_property`, or what another module derives and keeps with
:meth:`Memos.memo`), left out of its pickle and rebuilt on use."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import fields
from typing import Any

__all__ = ["Memos"]


class Memos:
    """Mixin of a frozen dataclass that keeps memos: its pickle holds its fields and
    nothing else, so a call that fills a memo leaves the object's pickle the same bytes,
    and a pickle never carries a memo, however large or deep (a circuit's reduction tree
    nests as deep as the network, deeper than pickle recurses)."""

    __slots__ = ()

    def __getstate__(self):
        return {f.name: self.__dict__[f.name] for f in fields(self)}   # type: ignore[arg-type]

    def memo(self, key: str, make: Callable[[], Any],
             valid: Callable[[Any], bool] = lambda value: True) -> Any:
        """``make()``, kept on this object under ``key``: built by the first call, the same
        object after while ``valid(it)`` holds (else built again).  For a module that
        caches what it derives from this object's fields (a circuit's state-space model,
        its resonances up to the largest ω asked); like every memo, never pickled."""
        memos = self.__dict__        # type: ignore[attr-defined]
        if key not in memos or not valid(memos[key]):
            memos[key] = make()
        return memos[key]
