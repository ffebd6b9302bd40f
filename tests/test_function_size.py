"""The package's functions stay short enough to read: none over 100 lines, at most 10 over 60.

A function's length is ``end_lineno - lineno + 1`` of its ``def`` (decorators not
counted, the docstring counted), for every function and method, nested ones included.
"""

import ast

from package_source import PACKAGE, package_trees, statements

MAX_LINES = 100
LONG = 60
MAX_LONG = 10


def function_lengths(tree: ast.Module) -> list[tuple[int, str, int]]:
    """(length, name, first line) of every function in ``tree``."""
    return [(node.end_lineno - node.lineno + 1, node.name, node.lineno)
            for node in statements(tree)
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))]


def test_lengths_are_counted_from_the_def_line():
    tree = ast.parse("@decorator\ndef f():\n    '''doc'''\n    return 1\n\n\ndef g():\n"
                     "    def h():\n        pass\n    return h\n")
    assert sorted(function_lengths(tree)) == [(2, "h", 8), (3, "f", 2), (4, "g", 7)]


def test_no_function_over_100_lines_and_few_over_60():
    rows = sorted(((n, f"{path.relative_to(PACKAGE.parent)}:{line} {name}")
                   for path, tree in package_trees().items()
                   for n, name, line in function_lengths(tree)), reverse=True)
    too_long = [f"{n} {where}" for n, where in rows if n > MAX_LINES]
    long = [f"{n} {where}" for n, where in rows if n > LONG]
    assert not too_long, f"functions over {MAX_LINES} lines: {too_long}"
    assert len(long) <= MAX_LONG, f"{len(long)} functions over {LONG} lines: {long}"
