"""``python -m mechcirc`` runs the command line."""

import sys

try:
    from .cli import main

    status = main()
except KeyboardInterrupt:           # Ctrl-C while the command line was still starting
    print("mechcirc: interrupted", file=sys.stderr)
    status = 130
sys.exit(status)
