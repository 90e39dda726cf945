"""``python -m sh_lighting <command> ...``: the command line of ``sh_lighting.cli``."""

import signal
import sys



def _interrupted(signum, frame):
    print("sh_lighting: interrupted", file=sys.stderr, flush=True)
    sys.exit(128 + signum)


# A signal before the command line takes over (cli.interrupts) ends the run cleanly too.
signal.signal(signal.SIGINT, _interrupted)
signal.signal(signal.SIGTERM, _interrupted)

from .cli import interrupts, main  # noqa: E402

if __name__ == "__main__":
    status = main(sys.argv[1:])
    interrupts.finished()  # the work is done: a late signal cannot kill Blender's shutdown
    sys.exit(status)
