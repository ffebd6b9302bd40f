"""mechcirc.sources: the declared TOML tables and located key errors shared by every reader;
lines counted as ``wc -l`` counts them (only \\n ends a line)."""

from __future__ import annotations

import pytest

from mechcirc.errors import NetlistError
from mechcirc.sources import (Table, check_keys, line_col, load_toml, locate_path, located,
                              split_lines, unknown_key)

TOP = Table(None, {"name": "a name", "omega": "[omega]"})
OMEGA = Table("omega", {"min": "lowest", "max": "highest"})
ITEMS = Table("items", {"a": "x", "b": "y"}, array=True)


def test_unknown_key_names_the_first_undeclared_key_in_file_order():
    assert unknown_key(OMEGA, {"min": 1, "max": 2}) is None
    assert unknown_key(OMEGA, {"min": 1, "zz": 2, "aa": 3}) == \
        ("zz", "unknown key 'zz' in [omega]")
    assert unknown_key(TOP, {"colour": 1}) == ("colour", "unknown top-level key 'colour'")
    assert unknown_key(ITEMS, {"c": 1}, 2) == ("c", "unknown key 'c' in [[items]] #3")
    assert OMEGA.expected == "min, max" and ITEMS.header == "[[items]]"


def test_check_keys_places_the_error_at_the_key():
    text = "name = 'x'\n[omega]\nmin = 1\nmx = 2\n[[items]]\na = 1\n[[items]]\nb = 1\nc = 2\n"
    doc = load_toml(text, "f.toml")
    check_keys(text, "f.toml", TOP, {k: v for k, v in doc.items() if k != "items"})
    with pytest.raises(NetlistError) as info:
        check_keys(text, "f.toml", OMEGA, doc["omega"])
    assert (info.value.line, info.value.col, info.value.expected) == (4, 1, "min, max")
    check_keys(text, "f.toml", ITEMS, doc["items"][0], 0)
    with pytest.raises(NetlistError, match=r"unknown key 'c' in \[\[items\]\] #2") as info:
        check_keys(text, "f.toml", ITEMS, doc["items"][1], 1)
    assert (info.value.line, info.value.col) == (9, 1)


def test_an_undeclared_top_level_table_is_placed_at_its_header():
    text = "name = 'x'\n\n[bogus.sub]\nx = 1\n"
    with pytest.raises(NetlistError, match="unknown top-level key 'bogus'") as info:
        check_keys(text, "f.toml", TOP, load_toml(text, "f.toml"))
    assert (info.value.line, info.value.col) == (3, 2)


def test_one_placement_for_every_reader():
    """The study reader (locate_path) and the scene and linkage readers (located) place an
    error the same way: at a table's header they pointed at '[' and at the name (now the
    name), and located did not look past [section] key = … (now also a key in an inline
    table, and the n-th [[section]]'s header when its key is missing)."""
    text = "name = 'x'\n\n[bogus.sub]\nx = 1\n"
    with pytest.raises(NetlistError) as info:
        check_keys(text, "f.toml", TOP, load_toml(text, "f.toml"))
    assert (info.value.line, info.value.col) == locate_path(text, ("bogus",)) == (3, 2)
    text = "grid = {eta = {min = 1, max = 2}}\n[[m]]\nk = 1\n[[m]]\nj = 2\n"
    assert located(text, "f", "x", "grid.eta", "max").col == 25 == \
        locate_path(text, ("grid", "eta", "max"))[1]
    assert (located(text, "f", "x", "m", "k", occurrence=1).line,
            located(text, "f", "x", "m", "k", occurrence=1).col) == (4, 3)


def test_locate_path_falls_back_to_a_sub_table_header():
    # [random] has no header of its own when only [random.params] is written
    text = "netlist = 'a'\n[random.params]\neta = {min = 1, max = 2}\n"
    assert locate_path(text, ("random", "n")) == (2, 2)      # the header's name
    assert locate_path(text, ("random", "params", "eta", "max")) == (3, 17)
    assert locate_path(text, ("nothing",)) == (0, 0)


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
    assert locate_path(text, ("omega",)) == (4, 2)


def test_locate_path_finds_dotted_keys():
    # Placed nowhere (0, 0) before: a dotted key is neither a header nor ``name =``.
    text = 'name = "x"\nground.points = ["a"]\n[grid]\neta2.num = 6\n'
    assert locate_path(text, ("ground", "points")) == (2, 8)
    assert locate_path(text, ("grid", "eta2", "num")) == (4, 6)
    assert locate_path(text, ("name",)) == (1, 1)


def test_number_error_is_one_message_for_every_reader():
    from mechcirc.sources import number_error

    assert number_error(2.5, "x") is None and number_error(0, "x", positive=True,
                                                           allow_zero=True) is None
    assert number_error(True, "x") == ("x must be a finite number, got True", "a finite number")
    assert number_error(0.0, "k [N/m]", positive=True) == \
        ("k [N/m] must be a finite number > 0, got 0.0", "a finite number > 0")
    assert number_error(-1, "c", positive=True, allow_zero=True)[1] == "a finite number ≥ 0"
    msg, _ = number_error(10 ** 400, "m")
    assert len(msg) < 120 and msg.endswith("...")      # a 400-digit integer, cut short


def test_checked_number_returns_the_float_or_raises_at_the_entrys_key():
    from mechcirc.sources import checked_number

    text = "[[m]]\nk = 1\n[[m]]\nk = -2\n"
    assert checked_number(text, "f.toml", 3, "k", "m", "k", positive=True) == 3.0
    with pytest.raises(NetlistError) as e:
        checked_number(text, "f.toml", -2, "k of #2", "m", "k", 1, positive=True)
    assert (e.value.line, e.value.col) == (4, 1)
    assert "k of #2 must be a finite number > 0, got -2" in str(e.value)
    assert "expected a finite number > 0" in str(e.value)
    with pytest.raises(NetlistError, match=r"expected k = a stiffness"):
        checked_number(text, "f.toml", "x", "k", "m", "k", expected="k = a stiffness")
