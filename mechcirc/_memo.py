"""Memos on plain data: values derived from a frozen dataclass's own fields and kept on
it (a :func:`functools.cached_property`, or a model another module caches in its
``__dict__``), left out of its pickle and rebuilt on use."""

from __future__ import annotations

from dataclasses import fields

__all__ = ["Memos"]


class Memos:
    """Mixin of a frozen dataclass that keeps memos: its pickle holds its fields and
    nothing else, so a call that fills a memo leaves the object's pickle the same bytes,
    and a pickle never carries a memo, however large or deep (a circuit's reduction tree
    nests as deep as the network, deeper than pickle recurses)."""

    __slots__ = ()

    def __getstate__(self):
        return {f.name: self.__dict__[f.name] for f in fields(self)}   # type: ignore[arg-type]
