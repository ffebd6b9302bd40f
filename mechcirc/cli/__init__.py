"""The ``mechcirc`` command line.

Each sub-command lives in a module of this package that exposes
``register(subparsers)``; handlers take the parsed arguments, make one API
call, print or write, and return an exit status.  Only this package prints or
exits.  Exit status: 0 success, 1 internal failure, 2 user error.

Handlers import numpy, matplotlib and friends inside their bodies, so
``mechcirc --help`` stays fast; a command line that names its command builds
only the parsers of that command's module (:data:`COMMANDS`).
"""

from __future__ import annotations

import argparse
import importlib
import re
import signal
import sys
import threading

from ..errors import did_you_mean, shorten

__all__ = ["main", "build_parser", "one_blas_thread"]

#: Each sub-command's module: ``mechcirc sweep ...``
#: imports and builds that module's parsers only.  A command missing here, or
#: registered elsewhere, still works: the full parser takes over (see
#: :class:`_OneModuleParser`); ``tests/test_startup.py`` keeps the table exact.
COMMANDS: dict[str, str] = {
    **dict.fromkeys(("check", "sweep", "resonances"), "mechcirc.cli.circuit_commands"),
    **dict.fromkeys(("fourbar", "frame", "synth", "linkage", "cam"),
                    "mechcirc.cli.kinematics_commands"),
    **dict.fromkeys(("simulate", "crosscheck"), "mechcirc.cli.sley_commands"),
    **dict.fromkeys(("forces", "compare", "formula", "study"),
                    "mechcirc.cli.ecosystem_commands"),
    **dict.fromkeys(("scene", "reduce"), "mechcirc.cli.scene_commands"),
    "transient": "mechcirc.cli.transient_commands",
    "periodic": "mechcirc.cli.periodic_commands",
}

#: Modules that contribute sub-commands, in the order ``--help`` lists them.
COMMAND_MODULES: list[str] = list(dict.fromkeys(COMMANDS.values()))


#: Options renamed, by command: the old spelling's error names the new one.
RENAMED: dict[tuple[str, str], str] = {("transient", "--drive"): "--waveform"}


class _Parser(argparse.ArgumentParser):
    """argparse, with a usage error on one line (the full usage is one ``--help`` away)."""

    #: The command word of the line (set by :func:`main`), named in a usage error.
    given: str | None = None
    #: The words of the line being parsed (set by the top-level parser as it starts; its
    #: commands' parsers read them): a missing required option may be a misspelt one.
    words: tuple[str, ...] = ()

    def parse_known_args(self, args=None, namespace=None):
        if any(isinstance(a, argparse._SubParsersAction) for a in self._actions):
            _Parser.words = tuple(sys.argv[1:] if args is None else args)
        return super().parse_known_args(args, namespace)

    def error(self, message):
        # 'invalid choice: 'swep' (choose from 'check', 'sweep', ...)': name the nearest
        if m := re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message):
            hint = did_you_mean(m.group(1), re.findall(r"'([^']*)'", m.group(2)))
            message = message.replace(m.group(0), m.group(0) + hint)
        if m := re.search(r"unrecognized arguments: (--[\w-]+)", message):
            message += self._option_hint(m.group(1).split("=")[0])
        # a bare word: a value of which option?
        if m := re.search(r"unrecognized arguments: ([^-\s]\S*)", message):
            message += self._value_hint(m.group(1))
        if message.startswith("the following arguments are required"):
            # argparse names what is missing before what it did not know: a misspelt
            # required option ('--omga') is both, and the misspelling is the answer.
            for word in (w.split("=")[0] for w in self.words if w.startswith("--")):
                if word not in self._option_string_actions:
                    hint = did_you_mean(word, sorted(self._option_string_actions))
                    message += f"; {word} is not an option{hint}"
        prog = self.prog
        # the command named as main() finds it (the first word not an option): its own
        # --help is the one that lists its options
        command = next((w for w in self.words if not w.startswith("-")), None)
        if message.startswith("unrecognized arguments") and command in COMMANDS:
            prog = f"{prog} {command}"
        self.exit(2, f"{prog}: error: {shorten(message)} (see '{prog} --help')\n")

    def _option_hint(self, word: str) -> str:
        """The nearest option of the command given, or which commands take ``word`` when
        it is another command's option (any command's nearest when none was given)."""
        subs = {name: p for action in self._actions
                if isinstance(action, argparse._SubParsersAction)
                for name, p in action.choices.items()}
        owners = [name for name, p in subs.items() if word in p._option_string_actions]
        if renamed := RENAMED.get((self.given or "", word)):
            return f"; {word} was renamed {renamed}"
        if self.given not in subs:
            options = set(self._option_string_actions).union(
                *(p._option_string_actions for p in subs.values()))
            return did_you_mean(word, sorted(options)) if not owners else \
                f"; {word} is an option of {', '.join(owners)}"
        hint = did_you_mean(word, sorted(subs[self.given]._option_string_actions))
        return (f"; {word} is an option of {', '.join(owners)}, not of {self.given}"
                if owners else "") + hint


    def _value_hint(self, word: str) -> str:
        """``"; did you mean '--load medium'?"`` when ``word`` is near a choice of an option
        of the command given (``mechcirc synth medum``)."""
        for action in self._actions:
            if isinstance(action, argparse._SubParsersAction) and self.given in action.choices:
                for opt in action.choices[self.given]._actions:
                    if opt.option_strings and opt.choices:      # (a sub-parser has none)
                        if hint := did_you_mean(word, opt.choices):
                            return hint.replace("'", f"'{opt.option_strings[-1]} ", 1)
        return ""


class _Retry(Exception):
    """A parser of one module's commands met an error: parse again with every command."""


class _OneModuleParser(_Parser):
    """The parser of one module's commands: any error is raised as :class:`_Retry`, so the
    full parser parses the line again and reports it as it always has."""

    def error(self, message):
        raise _Retry(message)


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """Build the argument parser with every sub-command registered (or ``command``'s module's).

    Parameters
    ----------
    command : str, optional
        A sub-command of :data:`COMMANDS`: only its module's commands are
        registered, and a usage error raises ``_Retry`` instead of exiting
        (:func:`main` then parses with the full parser).  None (or an unknown
        name): every command.

    Returns
    -------
    argparse.ArgumentParser
    """
    modules = [COMMANDS[command]] if command in COMMANDS else COMMAND_MODULES
    parser = (_OneModuleParser if command in COMMANDS else _Parser)(
        prog="mechcirc",
        description="Dynamic analysis of mechanisms with mechanical circuits: "
                    "netlists to K(ω) = v/Q and Q0 = V0/K, kinematics, sley dynamics.",
        epilog="Example: mechcirc sweep netlists/stb_heald.mcir --omega-min 10 "
               "--omega-max 1e4 --log -o K.csv --plot K.png",
    )
    from .. import __version__

    parser.add_argument("--version", action="version", version=f"mechcirc {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in modules:
        importlib.import_module(name).register(sub)
    # --debug is global, but the internal-error hint says "run again with --debug",
    # which users append after the command: each command takes it too.  SUPPRESS
    # keeps a command's parser from resetting a --debug given before the command
    # (absent, it is False: cli._common reads it with getattr).
    for each in [parser, *{id(p): p for p in sub.choices.values()}.values()]:
        each.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                          help="show the full traceback of an internal error")
    return parser


#: The variables OpenBLAS (numpy's and scipy's BLAS) reads for its thread count, in its
#: order of precedence: when the user set any of them, the command line leaves them be.
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS")


def one_blas_thread(environ) -> bool:
    """Ask OpenBLAS for one thread, unless the user chose a count; True when it was set.

    A command's arrays are small, and OpenBLAS starts its pool of threads when
    numpy is imported: on two cores that costs 25-100 ms of CPU time at each
    start (``import numpy`` measured 0.254 against 0.155 s on a quiet machine,
    0.209 against 0.185 s at load 9), as much as a sweep of the bundled netlist
    costs beyond ``import numpy``.  Called by
    :func:`main` for the process's own command line, before numpy is imported
    (afterwards the variable would change nothing but the environment of the
    processes the command starts), never by ``import mechcirc``.

    Parameters
    ----------
    environ : MutableMapping[str, str]
        The environment (``os.environ``): ``OPENBLAS_NUM_THREADS=1`` is set in it
        unless one of :data:`BLAS_THREAD_VARIABLES` is already there.

    Returns
    -------
    bool
        Whether the variable was set.
    """
    if any(name in environ for name in BLAS_THREAD_VARIABLES):
        return False
    environ["OPENBLAS_NUM_THREADS"] = "1"
    return True


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the exit status (also used by ``python -m mechcirc``).

    Parameters
    ----------
    argv : list of str, optional
        The arguments (``sys.argv[1:]`` when None).

    Returns
    -------
    int
        0 success, 1 internal failure, 2 user error, 130 interrupted.
    """
    if argv is None and "numpy" not in sys.modules:
        # The process's own command line (not a program calling main(argv)), and
        # numpy not loaded yet: one BLAS thread unless the user chose.
        import os

        one_blas_thread(os.environ)
    if threading.current_thread() is threading.main_thread():
        # From here on Ctrl-C raises KeyboardInterrupt, which the handlers unwind.
        signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        from ._common import join_spaced_quantities, run_handler, sigterm_unwinds

        argv = join_spaced_quantities(sys.argv[1:] if argv is None else argv)
        # The command is the first word that is not an option (the top level's
        # options, --help, --version and --debug, take no value).
        command = next((a for a in argv if not a.startswith("-")), None)
        try:
            parser = build_parser(command)
            args = parser.parse_args(argv)
        except _Retry:
            parser = build_parser()
            if isinstance(parser, _Parser):
                parser.given = command
            args = parser.parse_args(argv)
        if not getattr(args, "func", None):     # no command: the help, as a usage error
            parser.print_help(sys.stderr)
            return 2
        with sigterm_unwinds():
            return run_handler(args)
    except KeyboardInterrupt:       # Ctrl-C before the command's own handler took over
        print("mechcirc: interrupted", file=sys.stderr)
        return 130
