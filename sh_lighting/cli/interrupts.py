"""Ctrl+C (SIGINT) and SIGTERM: a command stops, nothing it was writing is moved into place,
and it exits with 128 + the signal's number (130, 143) after one line, ``sh_lighting:
interrupted``.

Importing bpy installs Blender's own SIGINT handler, which only notes the key press: a Ctrl+C
during Blender's start was swallowed and the command went on to replace its output.
So the handlers are installed before anything else, the two signals are held
(blocked, not lost) while bpy loads and our handlers are installed again before they are let
through, and ``check`` is called before each final move into place, in case the signal was
taken while Blender ran Python code of its own that ignores exceptions.

Work inside Blender's C code that swallows the KeyboardInterrupt (Cycles' bake prints it and
goes on baking) runs under ``at_once``: the signal ends the process within milliseconds.
"""

import os
import shutil
import signal
import sys
import threading
from contextlib import contextmanager

SIGNALS = (signal.SIGINT, signal.SIGTERM)
# The signal that stopped the command: a signal handler has no caller to return it to, and
# signals belong to the process, so the process's one record of it lives here.
_received = []


def _handler(signum, frame):
    if not _received:
        _received.append(signum)
    raise KeyboardInterrupt


def install():
    """Our handler for SIGINT and SIGTERM (only the main thread may install one)."""
    if threading.current_thread() is not threading.main_thread():
        return
    for signum in SIGNALS:
        signal.signal(signum, _handler)


@contextmanager
def held():
    """SIGINT and SIGTERM blocked during the block; our handlers installed again after it,
    then a signal that came meanwhile is delivered (a KeyboardInterrupt)."""
    blocked = threading.current_thread() is threading.main_thread()
    if blocked:
        signal.pthread_sigmask(signal.SIG_BLOCK, SIGNALS)
    try:
        yield
    finally:
        if blocked:
            install()
            signal.pthread_sigmask(signal.SIG_UNBLOCK, SIGNALS)


def _note(signum, frame):
    if not _received:
        _received.append(signum)


@contextmanager
def at_once():
    """During the block, SIGINT or SIGTERM end the process at once: the line ``sh_lighting:
    interrupted``, Blender's session temp folder removed, exit 128 + the signal's number.

    For work that writes nothing the user keeps (a bake into memory) inside C code that would
    not stop for a KeyboardInterrupt: Python's C-level handler writes the signal's number to a
    pipe (``signal.set_wakeup_fd``) even while the main thread is in Cycles, and a thread
    waiting on it ends the process (``os._exit``: nothing else runs, no traceback). A signal
    that comes as the block ends is delivered after it, as a KeyboardInterrupt.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    bpy = sys.modules.get("bpy")
    tempdir = getattr(getattr(bpy, "app", None), "tempdir", "") if bpy else ""
    read, write = os.pipe()
    os.set_blocking(write, False)
    done = threading.Event()

    def watch():
        data = os.read(read, 1)
        if done.is_set() or not data:
            return
        print("sh_lighting: interrupted", file=sys.stderr, flush=True)
        if tempdir and os.path.basename(os.path.normpath(tempdir)).startswith("blender_"):
            shutil.rmtree(tempdir, ignore_errors=True)
        os._exit(128 + data[0])

    watcher = threading.Thread(target=watch, name="sh_lighting interrupts", daemon=True)
    watcher.start()
    previous_fd = signal.set_wakeup_fd(write, warn_on_full_buffer=False)
    for signum in SIGNALS:
        signal.signal(signum, _note)
    try:
        yield
    finally:
        done.set()
        signal.set_wakeup_fd(previous_fd)
        install()
        os.write(write, b"\0")  # ends the watcher
        watcher.join()
        os.close(read)
        os.close(write)
        check()


def import_bpy():
    """``import bpy`` with the signals held (a no-op inside Blender, where it is loaded)."""
    with held():
        import bpy  # noqa: F401


def check():
    """A KeyboardInterrupt if a signal came (called before a file is moved into place)."""
    if _received:
        raise KeyboardInterrupt


def finished():
    """The command's work is done (its files are in place): a signal from now until the
    process ends is held, not delivered, so a late Ctrl+C cannot turn a finished run into a
    death by signal during Blender's shutdown. Only for ``python -m sh_lighting``, whose
    process ends next (a caller of ``main`` in its own process keeps its signals)."""
    if threading.current_thread() is threading.main_thread():
        signal.pthread_sigmask(signal.SIG_BLOCK, SIGNALS)


def exit_status():
    """128 + the number of the signal that stopped the command (130 for a plain Ctrl+C)."""
    return 128 + (_received[0] if _received else signal.SIGINT)
