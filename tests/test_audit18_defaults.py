"""The default of an option that ``refuse_ignored`` governs is written once, at its
registration (audit18): a :class:`Default` there marks the option as not given and holds
its value, and the help text states the same value (no second copy in the rule to drift)."""

import re

from mechcirc.cli import build_parser
from mechcirc.cli._common import Default, refuse_ignored


def _governed():
    """(command, option, Default, help) of every option registered with a Default."""
    top = build_parser()
    sub = next(a for a in top._actions if a.choices and isinstance(a.choices, dict))
    for command, parser in sub.choices.items():
        for action in parser._actions:
            if isinstance(action.default, Default):
                yield command, action.option_strings[-1], action.default, action.help or ""


def test_registered_defaults_and_their_help_agree():
    found = list(_governed())
    options = {(c, o) for c, o, _, _ in found}
    assert {("sweep", "--tol"), ("study", "--connect-timeout"), ("periodic", "--near"),
            ("scene", "--harmonics"), ("simulate", "--variant"), ("crosscheck", "--drive"),
            ("synth", "--c4"), ("frame", "--beat-window")} <= options
    stated = 0
    for command, option, default, text in found:
        m = re.search(r"\(default ([^,;)°\s]+)", text)
        if m:
            stated += 1
            word, value = m.group(1), default.value
            same = (float(word) == value if isinstance(value, (int, float)) else word == value)
            assert same, (command, option, word, value)
    assert stated >= 15


def test_not_given_takes_the_registered_value_and_given_is_refused():
    from argparse import Namespace

    from mechcirc.errors import InputError

    args = Namespace(tol=Default(0.005), refine=Default(True))
    refuse_ignored(args, {"--tol": (False, "--adaptive sweeps", "add --adaptive"),
                          "--no-refine": (False, "a fixed grid", "")})
    assert (args.tol, args.refine) == (0.005, True)
    try:
        refuse_ignored(Namespace(tol=1e-3), {"--tol": (False, "--adaptive sweeps",
                                                       "add --adaptive")})
    except InputError as exc:
        assert str(exc) == ("--tol applies to --adaptive sweeps (leave --tol out, or add "
                            "--adaptive)")
    else:
        raise AssertionError("--tol given without --adaptive was not refused")
