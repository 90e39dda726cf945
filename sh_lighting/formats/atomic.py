"""Atomic file writes: a file is either fully written or untouched, never half-written.

``write_text_atomic`` writes a temporary file beside the destination
(``.<name>.<pid>-<12 hex><suffix>``, O_EXCL), flushes it, and moves it into place with
``os.replace``; on any error (KeyboardInterrupt included) it is removed. A replaced file keeps
its permission bits and owner, a symbolic link is written through, and nothing is replaced
without ``overwrite=True``. ``atomic_destination`` does the same for other writers;
``leftovers`` / ``remove_leftovers`` find and delete the temporaries of killed writers (pid
provably gone: no such pid, a zombie or exiting one, or
one started after the file was written). Details: docs/modules.md.
"""

import errno
import os
import re
import secrets
import stat
from contextlib import contextmanager
from pathlib import Path

_TOKEN_DIGITS = 12  # secrets.token_hex(6)
_LEFTOVER = re.compile(
    rf"^\.(?P<name>.+)\.(?:(?P<pid>\d+)-)?[0-9a-f]{{{_TOKEN_DIGITS}}}(?P<suffix>\.[^.]+)$"
)
OLD_LEFTOVER_AGE = 2 * 3600.0  # s: a temporary name without a pid (an earlier version's)


def _exists_error(path, what, hint):
    return FileExistsError(f"{what} '{path}' already exists: choose another name, or {hint}")


def real_destination(path):
    """Where writing ``path`` puts the bytes: the target of a symbolic link (followed to the
    end, relative links resolved against the link's folder), else ``path`` itself."""
    path = Path(path)
    return Path(os.path.realpath(path)) if path.is_symlink() else path


def check_destination(path, overwrite, what, hint):
    """The real destination of ``path`` (``real_destination``), or a clear OSError."""
    path = Path(path)
    if path.is_dir():
        raise IsADirectoryError(f"{what} '{path}' is a folder: give a file name")
    if not overwrite and path.exists():
        raise _exists_error(path, what, hint)
    real = real_destination(path)
    if real.is_dir():
        raise IsADirectoryError(f"{what} '{path}' links to a folder: give a file name")
    folder = real.parent
    if folder.exists() and not folder.is_dir():
        raise NotADirectoryError(f"'{folder}' is a file, not a folder: {what} '{path}' "
                                 "cannot be written under it")
    if not folder.is_dir():
        raise FileNotFoundError(f"folder '{folder}' does not exist: create it first")
    return real


def temporary_path(path, suffix=".tmp"):
    """A fresh hidden path next to ``path`` (same folder, so ``os.replace`` is atomic)."""
    path = Path(path)
    token = secrets.token_hex(_TOKEN_DIGITS // 2)
    return path.parent / f".{path.name}.{os.getpid()}-{token}{suffix}"


def _writer_gone(pid, entry, now):
    """Whether the run that made the temporary file ``entry`` has provably ended."""
    if pid is None:  # an earlier version's name: only an old one is surely abandoned
        try:
            return now - entry.stat(follow_symlinks=False).st_mtime > OLD_LEFTOVER_AGE
        except OSError:
            return False
    pid = int(pid)
    if pid <= 0 or pid == os.getpid():
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except OverflowError:
        return False
    except OSError:  # PermissionError: another user's process runs (or ran: /proc tells)
        pass
    return _not_the_writer(pid, entry)


_PF_EXITING = 0x4  # the kernel's flag of a process in exit (a SIGKILL delivered)
_BOOT = re.compile(rb"^btime (\d+)$", re.M)


def _not_the_writer(pid, entry):
    """Whether the live pid ``pid`` provably no longer writes ``entry``, from Linux's
    ``/proc/<pid>/stat`` (state, flags, start time): a zombie or dead process, one that is
    exiting, or one started after ``entry`` was last written (the pid reused). False where
    nothing tells (another system, a file that vanished)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_bytes().rsplit(b")", 1)[1].split()
        state, flags, started = fields[0], int(fields[6]), int(fields[19])
    except (OSError, IndexError, ValueError):
        return False
    if state in (b"Z", b"X", b"x") or flags & _PF_EXITING:
        return True
    try:
        boot = _BOOT.search(Path("/proc/stat").read_bytes())
        written = entry.stat(follow_symlinks=False).st_mtime
    except OSError:
        return False
    if boot is None:
        return False
    # btime is whole seconds, rounded down: the start computed is at most 1 s early; a
    # second's margin more for a clock stepped meanwhile.
    start = int(boot[1]) + started / os.sysconf("SC_CLK_TCK")
    return start > written + 1.0


def leftovers(folder, name=None, now=None):
    """The temporary files of interrupted writes in ``folder`` (sorted) whose writer is
    gone, all of them or only those of the destination file ``name``."""
    import time

    now = time.time() if now is None else now
    folder = Path(folder)
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return []
    found = []
    for entry in entries:
        match = _LEFTOVER.match(entry.name)
        if (match and (name is None or match["name"] == name)
                and entry.is_file(follow_symlinks=False)
                and _writer_gone(match["pid"], entry, now)):
            found.append(folder / entry.name)
    return sorted(found)


def remove_leftovers(folder, name=None, now=None):
    """Delete ``leftovers(folder, name)``; returns the paths removed (a file that cannot be
    removed is left and not listed)."""
    removed = []
    for path in leftovers(folder, name, now):
        try:
            os.unlink(path)
        except OSError:
            continue
        removed.append(path)
    return removed


def _create(temporary, what, path):
    """Create ``temporary`` with O_EXCL (0o666: the umask decides); returns its fd.

    A folder that cannot be written is reported by the destination's name, not ours.
    """
    try:
        return os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    except OSError as error:
        if error.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
            raise PermissionError(
                error.errno,
                f"cannot write {what} '{path}': folder '{temporary.parent}' is not writable "
                f"({os.strerror(error.errno)}); choose another folder or change its permissions",
            ) from None
        raise OSError(error.errno, f"cannot write {what} '{path}': {os.strerror(error.errno)}") \
            from None


def _keep_mode_and_owner(temporary, real):
    """Give ``temporary`` the permission bits (and owner, where allowed) of ``real``."""
    try:
        st = os.stat(real)
    except FileNotFoundError:
        return  # a new file: the umask's permissions
    os.chmod(temporary, stat.S_IMODE(st.st_mode))
    if not hasattr(os, "chown"):
        return
    mine = os.stat(temporary)
    for uid, gid in ((st.st_uid, st.st_gid), (-1, st.st_gid)):
        if (mine.st_uid, mine.st_gid) == (st.st_uid, st.st_gid):
            return
        try:  # only root may give a file away; a group of ours may still be kept
            os.chown(temporary, uid, gid)
            os.chmod(temporary, stat.S_IMODE(st.st_mode))  # chown may clear set-id bits
            return
        except OSError:
            continue


def _discard(path):
    try:
        os.unlink(path)
    except FileNotFoundError:
        pass


def _move_into_place(temporary, path, real, overwrite, what, hint):
    """Mode and owner kept, the last existence check, then ``os.replace`` of the finished
    temporary file over ``real`` (the destination, or the target of its link)."""
    if not overwrite and path.exists():
        raise FileExistsError(
            f"{what} '{path}' appeared while it was being written: choose another name, "
            f"or {hint}"
        )
    _keep_mode_and_owner(temporary, real)
    os.replace(temporary, real)


def write_text_atomic(path, text, overwrite=False, what="file", hint="pass overwrite=True"):
    """Write ``text`` (str, UTF-8, ``\\n`` line ends) to ``path`` atomically; returns the Path.

    FileExistsError if ``path`` exists and ``overwrite`` is false; FileNotFoundError if its
    folder does not exist; IsADirectoryError if it is a folder; PermissionError naming
    ``path`` if its folder cannot be written. ``what`` and ``hint`` word the error messages
    ("preset file", "enable Overwrite").
    """
    path = Path(path)
    real = check_destination(path, overwrite, what, hint)
    data = text.encode("utf-8")  # encoding errors raise before anything touches the disk
    temporary = temporary_path(real)
    fd = _create(temporary, what, path)
    try:
        try:
            stream = os.fdopen(fd, "wb")
        except BaseException:
            os.close(fd)
            raise
        try:
            with stream:
                stream.write(data)
                stream.flush()
                os.fsync(stream.fileno())
        except OSError as error:  # a full disk, a quota: say which file could not be written
            raise OSError(error.errno, f"cannot write {what} '{path}': "
                          f"{error.strerror or error}") from None
        _move_into_place(temporary, path, real, overwrite, what, hint)
    except BaseException:
        _discard(temporary)
        raise
    return path


@contextmanager
def atomic_destination(path, overwrite=False, suffix=".tmp", what="file",
                       hint="pass overwrite=True"):
    """Context manager: yields a temporary Path to write; moves it to ``path`` on success.

    The folder is probed first (a temporary file created and removed, so an unwritable
    folder is reported here by ``path``'s name); the caller (or a program it runs) then writes
    the temporary file (it does not exist yet: writers that keep backups of a file they
    overwrite, like Blender's Save Versions, make none). When the block ends
    without an exception the file is moved over ``path`` (or the target of its link) with
    ``os.replace``, keeping the mode and owner of the file it replaces. If the block raises,
    or left no file, the temporary file is removed and ``path`` is untouched
    (FileNotFoundError in the second case). ``suffix`` lets writers that choose the format from
    the extension (``.blend``, ``.png``) see the right one.
    """
    path = Path(path)
    real = check_destination(path, overwrite, what, hint)
    temporary = temporary_path(real, suffix)
    os.close(_create(temporary, what, path))
    os.unlink(temporary)
    try:
        yield temporary
        if not temporary.is_file():
            raise FileNotFoundError(f"nothing was written for {what} '{path}'")
        _move_into_place(temporary, path, real, overwrite, what, hint)
    except BaseException:
        _discard(temporary)
        raise
