"""Ctrl+C (SIGINT) and SIGTERM: a command stops, nothing it was writing is moved into place,
and it exits with 128 + the signal's number (130, 143) after one line, ``sh_lighting:
interrupted``.

Importing bpy installs Blender's own SIGINT handler, which only notes the key press: a Ctrl+C
during Blender's start was swallowed and the command went on to replace its output.
So the handlers are installed before anything else, the two signals are held
(blocked, not lost) while bpy loads and our handlers are installed again before they are let
through, and ``check`` is called before each final move into place, in case the signal was
taken while Blender ran Python code of its own that ignores exceptions.
"""

import signal
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
