"""What the command line tells the user: progress on stdout, one error line on stderr.

A command raises ``CommandError`` with one sentence saying what is wrong and what to do;
``main`` prints it as ``sh_lighting: error: ...`` and exits with status 1.
"""

import sys


class CommandError(Exception):
    """A failure to report as one line on stderr (exit status 1)."""


def say(*args, **kwargs):
    """A line of progress or result on stdout, flushed (a farm log shows it at once)."""
    print(*args, **kwargs, flush=True)


def error_line(message):
    """``sh_lighting: error: message`` on stderr."""
    print(f"sh_lighting: error: {message}", file=sys.stderr, flush=True)
