"""``python -m mechcirc`` runs the command line.

``import mechcirc`` loads nothing but the error classes, so a Ctrl-C while the
command line starts arrives here (or in :func:`mechcirc.cli.main`, which puts
Python's own SIGINT handler in place) and ends it quietly with status 130.
"""

import sys

try:
    from .cli import main

    status = main()
except KeyboardInterrupt:           # Ctrl-C while the command line was still starting
    print("mechcirc: interrupted", file=sys.stderr)
    status = 130
sys.exit(status)
