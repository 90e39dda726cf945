"""``python -m sh_lighting <command> ...``: the command line of ``sh_lighting.cli``."""

import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
