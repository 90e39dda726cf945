"""Atomic file writes: a file is either fully written or untouched, never half-written.

``write_text_atomic`` writes the whole text to a temporary file in the destination's folder
(``.<name>.<random>.tmp``, created with O_EXCL so nothing existing is reused), flushes it to
disk, then moves it over the destination with ``os.replace`` (atomic on POSIX and Windows for
a file in the same folder). On any error, KeyboardInterrupt included, the temporary file is
removed and the destination keeps its previous content (or stays absent).

An existing destination is only replaced with ``overwrite=True``. Existence is checked before
writing and again just before the move; a file created by another program between that last
check and the move is replaced (no portable way to refuse it exists).

``atomic_destination`` hands out such a temporary path for writers that are not plain text
(e.g. a program that writes the file itself) and does the same checks and the final move.
"""

import os
import secrets
from contextlib import contextmanager
from pathlib import Path


def _exists_error(path, what, hint):
    return FileExistsError(f"{what} '{path}' already exists: choose another name, or {hint}")


def _check_destination(path, overwrite, what, hint):
    path = Path(path)
    if path.is_dir():
        raise IsADirectoryError(f"{what} '{path}' is a folder: give a file name")
    if not overwrite and path.exists():
        raise _exists_error(path, what, hint)
    folder = path.parent
    if not folder.is_dir():
        raise FileNotFoundError(f"folder '{folder}' does not exist: create it first")
    return path


def temporary_path(path, suffix=".tmp"):
    """A fresh hidden path next to ``path`` (same folder, so ``os.replace`` is atomic)."""
    path = Path(path)
    return path.parent / f".{path.name}.{secrets.token_hex(6)}{suffix}"


def _discard(path):
    try:
        os.unlink(path)
    except FileNotFoundError:
        pass


def _move_into_place(temporary, path, overwrite, what, hint):
    """The last existence check, then ``os.replace`` of the finished temporary file."""
    if not overwrite and path.exists():
        raise FileExistsError(
            f"{what} '{path}' appeared while it was being written: choose another name, "
            f"or {hint}"
        )
    os.replace(temporary, path)


def write_text_atomic(path, text, overwrite=False, what="file", hint="pass overwrite=True"):
    """Write ``text`` (str, UTF-8, ``\\n`` line ends) to ``path`` atomically; returns the Path.

    FileExistsError if ``path`` exists and ``overwrite`` is false; FileNotFoundError if its
    folder does not exist; IsADirectoryError if it is a folder. ``what`` and ``hint`` word the
    error messages ("preset file", "enable Overwrite").
    """
    path = _check_destination(path, overwrite, what, hint)
    data = text.encode("utf-8")  # encoding errors raise before anything touches the disk
    temporary = temporary_path(path)
    # O_EXCL: never reuse an existing file; 0o666 lets the umask decide the permissions.
    fd = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    try:
        try:
            stream = os.fdopen(fd, "wb")
        except BaseException:
            os.close(fd)
            raise
        with stream:
            stream.write(data)
            stream.flush()
            os.fsync(stream.fileno())
        _move_into_place(temporary, path, overwrite, what, hint)
    except BaseException:
        _discard(temporary)
        raise
    return path


@contextmanager
def atomic_destination(path, overwrite=False, suffix=".tmp", what="file",
                       hint="pass overwrite=True"):
    """Context manager: yields a temporary Path to write; moves it to ``path`` on success.

    The caller (or a program it runs) writes the temporary file; when the block ends without
    an exception the file is moved over ``path`` with ``os.replace``. If the block raises, or
    left no file behind, the temporary file is removed and ``path`` is untouched
    (FileNotFoundError in the second case). ``suffix`` lets writers that choose the format from
    the extension (``.blend``, ``.png``) see the right one.
    """
    path = _check_destination(path, overwrite, what, hint)
    temporary = temporary_path(path, suffix)
    try:
        yield temporary
        if not temporary.is_file():
            raise FileNotFoundError(f"nothing was written for {what} '{path}'")
        _move_into_place(temporary, path, overwrite, what, hint)
    except BaseException:
        _discard(temporary)
        raise
