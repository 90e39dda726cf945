"""Paths the commands read and write: inputs that must be files, ``//`` relative to the .blend,
outputs that are never an input, destinations checked before any work, leftovers of a killed
run. Every failure is a ``CommandError`` of one line."""

import os
from contextlib import contextmanager
from pathlib import Path

from ..formats.atomic import check_destination, real_destination, remove_leftovers
from .report import CommandError, say


def input_file(path, what, hint):
    """``path`` as a Path if it is an existing regular file, else a CommandError saying what
    it is instead (missing, a folder, a broken link, a device) and ``hint``."""
    path = Path(path)
    if path.is_file():
        return path
    if path.is_dir():
        raise CommandError(f"{what} '{path}' is a folder, not a file: {hint}")
    if path.is_symlink():
        raise CommandError(f"{what} '{path}' is a broken symbolic link (its target "
                           f"'{os.readlink(path)}' does not exist): {hint}")
    if path.exists():
        raise CommandError(f"{what} '{path}' is not a regular file: {hint}")
    raise CommandError(f"{what} '{path}' does not exist: {hint}")


def kind(path):
    """What a directory entry that is not a regular file is, for a message."""
    if path.is_dir():
        return "a folder, not a file"
    if path.is_symlink() and not path.exists():
        return f"a broken symbolic link (its target '{os.readlink(path)}' does not exist)"
    return "not a regular file"


def blend_relative(path, blend, flag):
    """``path`` (text) as a Path, a leading ``//`` taken relative to the folder of the .blend
    ``blend`` as Blender does; a CommandError when there is no .blend to be relative to."""
    if path is None:
        return None
    text = os.fspath(path)
    if not text.startswith("//"):
        return Path(text)
    if blend is None:
        raise CommandError(
            f"{flag} '{text}' starts with //, Blender's 'relative to the .blend file', but "
            "there is no .blend here: give the path without //"
        )
    return Path(os.path.dirname(os.path.abspath(blend))) / text[2:]


def same_file(a, b):
    """Whether paths ``a`` and ``b`` are one file (links, .., hard links: any path to it)."""
    try:
        return os.path.samefile(a, b)
    except OSError:  # one does not exist (yet): compare where they lead
        return os.path.realpath(a) == os.path.realpath(b)


def refuse_inputs(out, flag, inputs, advice="choose another name"):
    """A CommandError when ``out`` is one of ``inputs`` ({what: path}): no output ever
    replaces an input, whatever --overwrite says (checked before any other advice)."""
    for what, path in inputs.items():
        if path is not None and same_file(out, path):
            raise CommandError(
                f"{flag} '{out}' is the {what} '{path}' (the same file): an output never "
                f"replaces an input; {advice}"
            )


def check_new_file(path, overwrite, what="output", flag="--overwrite"):
    """Fail early, before any work, when ``path`` cannot be written (``atomic``'s own check,
    the one the write itself makes)."""
    try:
        check_destination(path, overwrite, what, f"pass {flag}")
    except OSError as error:
        raise CommandError(str(error)) from None


def file_in_way(path):
    """Whether a file (not a folder) stands where one of ``path``'s folders should be."""
    return any(p.exists() and not p.is_dir() for p in Path(path).parents)


def remove_own_leftovers(path):
    """Delete the temporary files a killed run left for the output ``path``; say so."""
    real = real_destination(path)
    for leftover in remove_leftovers(real.parent, real.name):
        say(f"removed {leftover.name}, left in {leftover.parent} by an interrupted run")


@contextmanager
def changed_alone(path, what):
    """Hold an exclusive lock (``flock``) on the file ``path`` during the block, or refuse in
    one line when another run holds it: two ``apply --in-place`` on one file never
    interleave (the lock goes with the open file, so Blender reading and writing the path
    does not release it; the file replaced at the end is a new one, free for the next run)."""
    import fcntl

    fd = os.open(path, os.O_RDONLY)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise CommandError(
                f"{what} '{path}' is being changed by another sh_lighting run: wait for it "
                "to end, then run again"
            ) from None
        yield
    finally:
        os.close(fd)
