"""mechcirc.sources: reading user files, lines counted as ``wc -l`` counts them, located keys."""

from __future__ import annotations

import pytest

from mechcirc.errors import NetlistError
from mechcirc.sources import line_col, locate_path, split_lines


@pytest.mark.parametrize("brk", ["\x0c", "\x0b", "\r", "\x85", "\u2028", "\u2029", "\x1c"])
def test_only_newlines_end_lines(brk, tmp_path, capsys):
    """A form feed, VT, lone CR, NEL or U+2028 is no line break (as wc -l and editors)."""
    text = f"mass m1 a 0 1{brk}\nspring k1 a 0 oops\ndrive V a 0 velocity=1\n"
    path = tmp_path / "ff.mcir"
    path.write_text(text, encoding="utf-8")
    n_lines = path.read_bytes().count(b"\n")             # what wc -l prints
    with pytest.raises(NetlistError) as info:
        import mechcirc

        mechcirc.load(path)
    assert info.value.line == 2 <= n_lines


def test_line_past_the_end_is_never_reported(tmp_path):
    import mechcirc

    text = "mass m1 a 0 1\x0cspring k1 a 0 oops\ndrive V a 0 velocity=1\n"
    with pytest.raises(NetlistError) as info:
        mechcirc.parse(text, "ff.mcir")
    assert info.value.line <= text.count("\n")


def test_split_lines_and_line_col():
    assert split_lines("a\r\nb\n") == ["a", "b"]
    assert split_lines("a\rb\x0cc\u2028d") == ["a\rb\x0cc\u2028d"]
    assert split_lines("") == [] and split_lines("\n") == [""]
    assert line_col("ab\ncd", 4) == (2, 2)


def test_locate_path_finds_inline_table_keys():
    text = "[grid]\neta1 = [1, 2]\neta2 = {min = 1, max = 2, num = 6}\n[omega]\nmin = 1\n"
    assert locate_path(text, ("grid", "eta2", "num")) == (3, 27)
    assert locate_path(text, ("omega", "min")) == (5, 1)
    assert locate_path(text, ("omega",)) == (4, 1)
