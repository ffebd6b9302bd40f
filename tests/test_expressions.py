import math

import pytest

from mechcirc.errors import NetlistError
from mechcirc.expressions import MAX_DEPTH, evaluate, parse_expression


def ev(text, **params):
    return evaluate(parse_expression(text), params)


@pytest.mark.parametrize("text, value", [
    ("1e5", 1e5), (".5", 0.5), ("2.", 2.0), ("2^3", 8.0), ("2**3**2", 512.0),
    ("-2**2", -4.0), ("(1+2)*3", 9.0), ("7/2", 3.5), ("--3", 3.0), ("+4", 4.0),
    ("sqrt(16)", 4.0), ("cos(pi)", -1.0), ("degrees(pi)", 180.0),
    ("radians(180)", math.pi), ("exp(log(3))", 3.0), ("2 * 3 - 4 / 8", 5.5),
])
def test_values(text, value):
    assert ev(text) == pytest.approx(value, rel=1e-15)


def test_parameters():
    assert ev("a*b + 1", a=2.0, b=3.0) == 7.0


@pytest.mark.parametrize("text, col, fragment", [
    ("1 +", 4, "ends too early"),
    ("(1 + 2", 1, "never closed"),
    ("1 + 2)", 6, "without a matching"),
    ("3 $ 4", 3, "unexpected character"),
    ("foo(2)", 1, "unknown function"),
    ("sqrt", 1, "needs an argument"),
    ("1 / 0", 3, "division by zero"),
    ("x + 1", 1, "undefined parameter"),
    ("9**9**9", 2, "overflows"),
    ("1e999", 1, "too large"),
    ("sqrt(-1)", 1, "undefined"),
    ("(-8)**0.5", 5, "not a real number"),
    ("", 1, "empty"),
])
def test_errors_have_columns(text, col, fragment):
    with pytest.raises(NetlistError) as info:
        ev(text)
    assert fragment in info.value.message
    assert info.value.col == col


def test_depth_limit_is_an_error_not_a_crash():
    with pytest.raises(NetlistError, match="nested more than"):
        ev("(" * (MAX_DEPTH + 5) + "1" + ")" * (MAX_DEPTH + 5))
    with pytest.raises(NetlistError, match="nested more than"):
        ev("-" * 5_000 + "1")


def test_length_limit():
    with pytest.raises(NetlistError, match="limit"):
        ev("1+" * 10_000 + "1")


@pytest.mark.parametrize("text, value, slope", [
    ("sqrt(x)", math.sqrt(2.0), 0.5 / math.sqrt(2.0)),
    ("sin(x)", math.sin(2.0), math.cos(2.0)),
    ("cos(x)", math.cos(2.0), -math.sin(2.0)),
    ("tan(x)", math.tan(2.0), 1 / math.cos(2.0) ** 2),
    ("exp(x)", math.exp(2.0), math.exp(2.0)),
    ("log(x)", math.log(2.0), 0.5),
    ("radians(x)", math.radians(2.0), math.pi / 180),
    ("degrees(x)", math.degrees(2.0), 180 / math.pi),
    ("x^3 / (1 + x) - 2*x", 8 / 3 - 4, 12 / 3 - 8 / 9 - 2),
    ("2^x", 4.0, 4 * math.log(2)),
    ("x^x", 4.0, 4 * (math.log(2) + 1)),
    ("-(x * y) + pi", -6.0 + math.pi, -3.0),
    ("0^2 + y", 3.0, 0.0),
])
def test_evaluate_with_a_tangent_gives_the_exact_derivative(text, value, slope):
    """d/dx at x = 2 (y = 3), against derivatives written by hand."""
    from mechcirc.expressions import evaluate, parse_expression

    v, d = evaluate(parse_expression(text), {"x": 2.0, "y": 3.0}, tangent={"x": 1.0})
    assert v == pytest.approx(value, rel=1e-15)
    assert d == pytest.approx(slope, rel=1e-14, abs=1e-15)
