"""The user's files: writes are all or nothing and never replace a file unless asked;
replaced files keep mode, owner and links; leftovers of a kill are found; preset reading
takes only small regular files and turns every decoding failure into one PresetError naming
the file."""

import errno
import os
import stat
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from sh_lighting.formats import atomic
from sh_lighting.formats.presets import MAX_PRESET_BYTES, PresetError, read_preset, write_preset

COEFFS = np.arange(27, dtype=np.float64).reshape(9, 3) / 8.0
OTHER = COEFFS + 1.0


def mode(path):
    return stat.S_IMODE(os.stat(path).st_mode)


def leftovers(folder):
    """Hidden temporary files a failed write could have left behind."""
    return sorted(p.name for p in Path(folder).iterdir() if p.name.startswith("."))


# --- writing: all or nothing, never over a file unless asked ----------------------------

OLD_TEXT = "previous content\n"


@pytest.fixture
def existing(tmp_path):
    path = tmp_path / "light.json"
    path.write_text(OLD_TEXT)
    return path


def test_existing_file_is_not_overwritten_by_default(existing):
    with pytest.raises(FileExistsError, match=r"already exists.*overwrite=True"):
        write_preset(existing, COEFFS)
    assert existing.read_text() == OLD_TEXT
    assert list(existing.parent.iterdir()) == [existing]


def test_overwrite_replaces(existing):
    write_preset(existing, COEFFS, overwrite=True)
    assert np.array_equal(read_preset(existing)[0], COEFFS)
    assert list(existing.parent.iterdir()) == [existing]


def test_new_file_gets_ordinary_permissions(tmp_path):
    path = write_preset(tmp_path / "new.json", COEFFS)
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask


class FailingStream:
    """Wraps a file object; writes half of the text, then fails like a full disk."""

    def __init__(self, stream):
        self.stream = stream

    def write(self, text):
        self.stream.write(text[: len(text) // 2])
        self.stream.flush()
        raise OSError(28, "No space left on device")

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stream.close()

    def __getattr__(self, name):
        return getattr(self.stream, name)


REAL_FDOPEN = os.fdopen


def failing_fdopen(*args, **kwargs):
    return FailingStream(REAL_FDOPEN(*args, **kwargs))


def raise_os_error(*args, **kwargs):
    raise OSError("simulated failure")


def raise_interrupt(*args, **kwargs):
    raise KeyboardInterrupt


@pytest.mark.parametrize(
    "target, replacement, error",
    [
        ("fdopen", failing_fdopen, OSError),  # half the text written, then a full disk
        ("fsync", raise_os_error, OSError),  # everything written, flushing to disk fails
        ("replace", raise_os_error, OSError),  # the final move fails
        ("replace", raise_interrupt, KeyboardInterrupt),  # the user interrupts at the last step
    ],
)
@pytest.mark.parametrize("overwrite", [False, True])
def test_a_failed_write_leaves_the_destination_untouched_and_no_temporary_file(
    tmp_path, monkeypatch, target, replacement, error, overwrite
):
    path = tmp_path / "light.json"
    if overwrite:
        path.write_text(OLD_TEXT)
    monkeypatch.setattr(atomic.os, target, replacement)
    with pytest.raises(error):
        write_preset(path, COEFFS, overwrite=overwrite)
    monkeypatch.undo()
    if overwrite:
        assert path.read_text() == OLD_TEXT
        assert list(tmp_path.iterdir()) == [path]
    else:
        assert list(tmp_path.iterdir()) == []


def test_a_file_appearing_during_the_write_is_not_replaced(tmp_path, monkeypatch):
    path = tmp_path / "light.json"
    real_fsync = os.fsync

    def fsync_then_someone_creates_the_file(fd):
        real_fsync(fd)
        path.write_text(OLD_TEXT)

    monkeypatch.setattr(atomic.os, "fsync", fsync_then_someone_creates_the_file)
    with pytest.raises(FileExistsError, match="appeared while it was being written"):
        write_preset(path, COEFFS)
    assert path.read_text() == OLD_TEXT
    assert list(tmp_path.iterdir()) == [path]


def test_missing_folder_is_reported(tmp_path):
    with pytest.raises(FileNotFoundError, match="does not exist: create it first"):
        write_preset(tmp_path / "no" / "such" / "light.json", COEFFS)


def test_failed_atomic_write_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch):
    path = tmp_path / "p.json"
    path.write_text("old")

    def broken_replace(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(atomic.os, "replace", broken_replace)
    with pytest.raises(OSError, match="disk full"):
        atomic.write_text_atomic(path, "new", overwrite=True)
    with pytest.raises(OSError, match="disk full"):
        with atomic.atomic_destination(path, overwrite=True) as temporary:
            temporary.write_text("new")
    assert path.read_text() == "old"
    assert leftovers(tmp_path) == []


def test_atomic_destination_refuses_missing_output_and_existing_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothing was written"):
        with atomic.atomic_destination(tmp_path / "out.bin"):
            pass  # the writer wrote nothing
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "x").write_text("a")
    with pytest.raises(FileExistsError, match="already exists"):
        with atomic.atomic_destination(tmp_path / "x"):
            pytest.fail("must refuse before the block runs")
    with pytest.raises(FileNotFoundError, match="does not exist"):
        atomic.write_text_atomic(tmp_path / "no" / "dir.json", "x")


# --- replacing a file keeps what the user set --------------------------------------------


@pytest.mark.parametrize("permissions", [0o600, 0o444, 0o640, 0o755])
def test_a_replaced_file_keeps_its_permissions(tmp_path, permissions):
    path = write_preset(tmp_path / "p.json", COEFFS)
    os.chmod(path, permissions)
    write_preset(path, OTHER, overwrite=True)
    assert mode(path) == permissions
    assert np.array_equal(read_preset(path)[0], OTHER)


def test_a_new_file_gets_the_umask_permissions(tmp_path):
    old = os.umask(0o027)
    try:
        path = write_preset(tmp_path / "new.json", COEFFS)
    finally:
        os.umask(old)
    assert mode(path) == 0o640


@pytest.mark.skipif(os.getuid() != 0, reason="giving a file to another user needs root")
def test_a_replaced_file_keeps_its_owner_where_the_system_allows(tmp_path):
    path = write_preset(tmp_path / "p.json", COEFFS)
    os.chown(path, 65534, 65534)
    os.chmod(path, 0o4640)  # chown clears set-id bits: they are set again afterwards
    write_preset(path, OTHER, overwrite=True)
    info = os.stat(path)
    assert (info.st_uid, info.st_gid, stat.S_IMODE(info.st_mode)) == (65534, 65534, 0o4640)


def test_atomic_destination_keeps_the_mode_too(tmp_path):
    path = tmp_path / "render.exr"
    path.write_bytes(b"old")
    os.chmod(path, 0o600)
    with atomic.atomic_destination(path, overwrite=True, suffix=".exr") as temporary:
        assert not temporary.exists()  # writers that back up an existing file make no backup
        temporary.write_bytes(b"new")
    assert path.read_bytes() == b"new" and mode(path) == 0o600
    assert sorted(p.name for p in tmp_path.iterdir()) == ["render.exr"]


def test_a_symbolic_link_is_written_through_to_its_target(tmp_path):
    (tmp_path / "store").mkdir()
    target = write_preset(tmp_path / "store" / "real.json", COEFFS)
    os.chmod(target, 0o600)
    link = tmp_path / "link.json"
    link.symlink_to(os.path.join("store", "real.json"))  # relative, as users make them
    chain = tmp_path / "chain.json"
    chain.symlink_to(link)
    write_preset(chain, OTHER, overwrite=True)
    assert chain.is_symlink() and link.is_symlink()
    assert os.readlink(link) == os.path.join("store", "real.json")
    assert np.array_equal(read_preset(target)[0], OTHER) and mode(target) == 0o600
    assert sorted(p.name for p in tmp_path.iterdir()) == ["chain.json", "link.json", "store"]
    assert sorted(p.name for p in (tmp_path / "store").iterdir()) == ["real.json"]


def test_an_unwritable_folder_is_named_not_our_temporary_file(tmp_path, monkeypatch):
    """os.open fails as it does in a read-only folder (the tests may run as root, for whom
    no folder is read-only): the message names the destination and its folder."""
    real_open = os.open

    def refuse(path, *args, **kwargs):
        if os.path.basename(path).startswith("."):
            raise PermissionError(errno.EACCES, "Permission denied", path)
        return real_open(path, *args, **kwargs)

    monkeypatch.setattr(atomic.os, "open", refuse)
    with pytest.raises(PermissionError) as caught:
        write_preset(tmp_path / "p.json", COEFFS)
    message = str(caught.value)
    assert f"cannot write preset file '{tmp_path / 'p.json'}'" in message
    assert f"folder '{tmp_path}' is not writable" in message
    assert ".tmp" not in message
    with pytest.raises(PermissionError, match="is not writable"):
        with atomic.atomic_destination(tmp_path / "x.blend", suffix=".blend"):
            pytest.fail("the block must not run when the folder cannot be written")


def test_a_file_in_the_way_of_the_folder_is_named(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(NotADirectoryError, match=r"is a file, not a folder"):
        write_preset(tmp_path / "file" / "p.json", COEFFS)


# --- what a kill leaves, found at the next run -------------------------------------------


def _dead_pid():
    import subprocess
    import sys

    finished = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                              capture_output=True, text=True, check=True)
    return int(finished.stdout)


def test_leftovers_of_killed_writes_are_found_by_name_and_removed(tmp_path):
    dead = _dead_pid()
    keep = ["p.json", ".hidden", ".p.json.tmp", ".p.json.0123456789ax.tmp", "notes.txt",
            f".p.json.{os.getpid()}-0123456789ab.tmp",  # this process is writing it
            ".p.json.1-0123456789ab.tmp",  # process 1 runs
            ".r.json.00ff00ff00ff.tmp"]  # an earlier version's name, a minute old
    for name in keep:
        (tmp_path / name).write_text("user data")
    ours = [f".p.json.{dead}-0123456789ab.tmp", f".q.json.{dead}-a1b2c3d4e5f6.tmp",
            f".s.blend.{dead}-00ff00ff00ff.blend@", ".t.json.0123456789ab.tmp"]
    for name in ours:
        (tmp_path / name).write_text("half written")
    now = (tmp_path / ours[3]).stat().st_mtime + atomic.OLD_LEFTOVER_AGE + 1
    os.utime(tmp_path / ".r.json.00ff00ff00ff.tmp", (now - 60, now - 60))
    (tmp_path / f".d.json.{dead}-abcdefabcdef.tmp").mkdir()  # a folder is never ours to delete
    assert [p.name for p in atomic.leftovers(tmp_path, now=now)] == sorted(ours)
    assert [p.name for p in atomic.leftovers(tmp_path, "s.blend", now=now)] == [ours[2]]
    assert [p.name for p in atomic.remove_leftovers(tmp_path, "p.json", now=now)] == [ours[0]]
    assert sorted(p.name for p in atomic.remove_leftovers(tmp_path, now=now)) == sorted(ours[1:])
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left == sorted(keep + [f".d.json.{dead}-abcdefabcdef.tmp"])


def test_a_temporary_name_is_what_leftovers_looks_for_once_its_writer_is_gone(tmp_path):
    temporary = atomic.temporary_path(tmp_path / "frame_0001.exr", ".exr")
    temporary.write_bytes(b"x")
    assert temporary.name.startswith(f".frame_0001.exr.{os.getpid()}-")
    assert atomic.leftovers(tmp_path, "frame_0001.exr") == []  # its writer (us) runs
    killed = temporary.with_name(temporary.name.replace(f".{os.getpid()}-", f".{_dead_pid()}-"))
    temporary.rename(killed)
    assert atomic.leftovers(tmp_path, "frame_0001.exr") == [killed]


def _state(pid):
    return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux's /proc")
def test_a_killed_writer_not_yet_reaped_is_gone(tmp_path):
    """A SIGKILLed writer whose parent has not reaped it yet (a zombie: ``kill(pid, 0)``
    still succeeds, for a second or more on a loaded machine) writes nothing any more."""
    import subprocess
    import time

    writer = subprocess.Popen(["sleep", "60"])
    try:
        temporary = tmp_path / f".shot_0004.exr.{writer.pid}-0123456789ab.exr"
        temporary.write_bytes(b"half a frame")
        assert atomic.leftovers(tmp_path, "shot_0004.exr") == []  # it runs: it may be writing
        writer.kill()
        deadline = time.monotonic() + 30
        while _state(writer.pid) != "Z":  # killed, not reaped (we do not wait() yet)
            assert time.monotonic() < deadline
            time.sleep(0.005)
        assert atomic.leftovers(tmp_path, "shot_0004.exr") == [temporary]
    finally:
        writer.kill()
        writer.wait()


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux's /proc")
def test_a_pid_reused_by_a_process_started_after_the_file_was_written_is_not_its_writer(
        tmp_path):
    import subprocess

    other = subprocess.Popen(["sleep", "60"])
    try:
        temporary = tmp_path / f".shot_0004.exr.{other.pid}-0123456789ab.exr"
        temporary.write_bytes(b"half a frame")
        assert atomic.leftovers(tmp_path, "shot_0004.exr") == []  # written since it started
        written = time.time() - 60  # a minute before this process started: not its file
        os.utime(temporary, (written, written))
        assert atomic.leftovers(tmp_path, "shot_0004.exr") == [temporary]
    finally:
        other.kill()
        other.wait()


# --- reading presets: small regular files only, one PresetError each ----------------------


@pytest.fixture
def valid(tmp_path):
    return write_preset(tmp_path / "valid.json", COEFFS).read_text()


@pytest.mark.parametrize("depth", [1000, 100_000])
def test_deep_nesting_is_one_preset_error_naming_the_file(tmp_path, valid, depth):
    path = tmp_path / "deep.json"
    path.write_text(valid.rstrip()[:-1] + ', "metadata": {"deep": ' + "[" * depth + "]" * depth
                    + "}}\n")
    with pytest.raises(PresetError, match=rf"preset file '{path}': its JSON is nested too deep"):
        read_preset(path)


def test_a_huge_integer_coefficient_is_refused_clearly(tmp_path, valid):
    path = tmp_path / "big.json"
    start = valid.index('"L00": [') + len('"L00": [')
    path.write_text(valid[:start] + "1" * 5000 + valid[valid.index(",", start):])
    with pytest.raises(PresetError, match=rf"preset file '{path}': its JSON cannot be read"):
        read_preset(path)
    path.write_text(valid[:start] + "1" * 400 + valid[valid.index(",", start):])
    with pytest.raises(PresetError, match=r"coefficient L00 channel R is inf"):
        read_preset(path)


def test_devices_fifos_folders_and_huge_files_are_not_read(tmp_path):
    with pytest.raises(PresetError, match=r"'/dev/zero' is not a regular file"):
        read_preset("/dev/zero")
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    outcome = []
    reader = threading.Thread(target=lambda: outcome.append(_error_of(read_preset, fifo)))
    reader.start()
    reader.join(timeout=10)
    alive = reader.is_alive()
    if alive:  # unblock the hung open so the test process can end, then fail
        with open(fifo, "w"):
            pass
    assert not alive, "reading a FIFO blocked"
    assert isinstance(outcome[0], PresetError) and "is not a regular file" in str(outcome[0])
    with pytest.raises(PresetError, match=r"is a folder: choose a preset file"):
        read_preset(tmp_path)
    big = tmp_path / "big.json"
    with open(big, "wb") as stream:
        stream.truncate(MAX_PRESET_BYTES + 1)
    with pytest.raises(PresetError, match=rf"holds {MAX_PRESET_BYTES + 1} bytes, more than"):
        read_preset(big)
    with pytest.raises(FileNotFoundError, match=r"preset file '.*absent.json' does not exist"):
        read_preset(tmp_path / "absent.json")


def _error_of(function, *args):
    try:
        function(*args)
    except Exception as error:  # noqa: BLE001 - the test inspects it
        return error
    return None


def test_a_full_disk_names_the_file_it_could_not_write(tmp_path, monkeypatch):
    """Not "[Errno 28] No space left on device" without the path."""
    def full(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    target = tmp_path / "sky.json"
    monkeypatch.setattr(os, "fsync", full)
    with pytest.raises(OSError) as caught:
        atomic.write_text_atomic(target, "{}", what="preset file")
    assert caught.value.errno == errno.ENOSPC
    assert str(caught.value) == (f"[Errno 28] cannot write preset file '{target}': "
                                 "No space left on device")
    assert list(tmp_path.iterdir()) == []  # nothing half written left behind
