"""What the command line tells the user: progress on stdout, one error line on stderr, and
before a step expected to take over ``LONG_SECONDS`` a line on stderr saying what runs.

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


# Work that takes at least this long gets its own line with its time (a stage of compute).
STAGE_LINE_SECONDS = 1.0


def stage_line(name, seconds, threshold=None):
    """``  name: 1.23 s`` on stdout when the stage took ``threshold`` (default
    ``STAGE_LINE_SECONDS``) or longer: the progress of a long compute, a line per stage."""
    if seconds >= (STAGE_LINE_SECONDS if threshold is None else threshold):
        say(f"  {name}: {seconds:.2f} s")


class timed_stage:  # noqa: N801 (used as ``with timed_stage("name"):``)
    """``with timed_stage("writing"):`` runs the block and then ``stage_line``s its time."""

    def __init__(self, name):
        self.name = name

    def __enter__(self):
        import time

        self.start = time.perf_counter()
        return self

    def __exit__(self, kind, value, traceback):
        import time

        if kind is None:
            stage_line(self.name, time.perf_counter() - self.start)
        return False


# A step expected to take at least this long says so on stderr before it starts (Blender's
# decode holds the interpreter: no line can come while it runs, so the line comes first).
LONG_SECONDS = 2.0


def before_long(text, expected):
    """``sh_lighting: text...`` on stderr when ``expected`` (s, an estimate) is at least
    ``LONG_SECONDS``: the user waiting sees what runs (stdout stays the command's results)."""
    if expected >= LONG_SECONDS:
        print(f"sh_lighting: {text}...", file=sys.stderr, flush=True)


def time_left(done, total, elapsed):
    """``"; about 12 s left"`` after ``done`` of ``total`` files in ``elapsed`` seconds (the mean
    so far times the files left), or "" when nothing is left or it is under a second."""
    left = total - done
    if done <= 0 or left <= 0:
        return ""
    seconds = elapsed / done * left
    if seconds < 1.0:
        return ""
    if seconds < 120:
        return f"; about {seconds:.0f} s left"
    return f"; about {seconds / 60:.0f} min left"
