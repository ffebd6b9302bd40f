"""The ``mechcirc`` command line.

Each sub-command lives in a module of this package that exposes
``register(subparsers)``; handlers take the parsed arguments, make one API
call, print or write, and return an exit status.  Only this package prints or
exits.  Exit status: 0 success, 1 internal failure, 2 user error.

Handlers import numpy, matplotlib and friends inside their bodies, so
``mechcirc --help`` stays fast.
"""

from __future__ import annotations

import argparse
import importlib

__all__ = ["main", "build_parser"]

#: Modules that contribute sub-commands, in the order ``--help`` lists them.
COMMAND_MODULES: list[str] = [
    "mechcirc.cli.circuit_commands",
    "mechcirc.cli.kinematics_commands",
    "mechcirc.cli.sley_commands",
    "mechcirc.cli.ecosystem_commands",
    "mechcirc.cli.scene_commands",
    "mechcirc.cli.transient_commands",
    "mechcirc.cli.periodic_commands",
]


class _Parser(argparse.ArgumentParser):
    """argparse, with a usage error on one line (the full usage is one ``--help`` away)."""

    def error(self, message):
        import re

        from ..errors import shorten  # argparse quotes the value given: it may be long
        from ..sources import did_you_mean

        # 'invalid choice: 'swep' (choose from 'check', 'sweep', ...)': name the nearest
        m = re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message)
        if m:
            hint = did_you_mean(m.group(1), re.findall(r"'([^']*)'", m.group(2)))
            message = message.replace(m.group(0), m.group(0) + hint)
        m = re.search(r"unrecognized arguments: (--[\w-]+)", message)
        if m:
            # parse_args reports it from the top parser: offer every command's options
            options = set(self._option_string_actions)
            for action in self._actions:
                if isinstance(action, argparse._SubParsersAction):
                    for p in action.choices.values():
                        options |= set(p._option_string_actions)
            message += did_you_mean(m.group(1).split("=")[0], sorted(options))
        self.exit(2, f"{self.prog}: error: {shorten(message)} (see '{self.prog} --help')\n")


def build_parser() -> argparse.ArgumentParser:
    """Build the argument parser with every sub-command registered.

    Returns
    -------
    argparse.ArgumentParser
    """
    parser = _Parser(
        prog="mechcirc",
        description="Dynamic analysis of mechanisms with mechanical circuits: "
                    "netlists to K(ω) = v/Q and Q0 = V0/K, kinematics, sley dynamics.",
        epilog="Example: mechcirc sweep netlists/stb_heald.mcir --omega-min 10 "
               "--omega-max 1e4 --log -o K.csv --plot K.png",
    )
    from .. import __version__

    parser.add_argument("--version", action="version", version=f"mechcirc {__version__}")
    parser.add_argument("--debug", action="store_true",
                        help="show the full traceback of an internal error")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    # --debug is global, but the internal-error hint says "run again with --debug",
    # which users append after the command: each command takes it too.  SUPPRESS
    # keeps a command's parser from resetting a --debug given before the command.
    for command in {id(p): p for p in sub.choices.values()}.values():
        command.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                             help="show the full traceback of an internal error")
    return parser


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
    import signal
    import sys
    import threading

    if threading.current_thread() is threading.main_thread():
        # From here on Ctrl-C raises KeyboardInterrupt, which the handlers unwind.
        signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        from ._common import join_spaced_quantities, run_handler, sigterm_unwinds

        parser = build_parser()
        args = parser.parse_args(join_spaced_quantities(sys.argv[1:] if argv is None
                                                        else argv))
        if not getattr(args, "func", None):
            parser.print_help()
            return 2
        with sigterm_unwinds():
            return run_handler(args)
    except KeyboardInterrupt:       # Ctrl-C before the command's own handler took over
        print("mechcirc: interrupted", file=sys.stderr)
        return 130
