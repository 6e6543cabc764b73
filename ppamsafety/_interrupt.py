"""Ctrl-C that cannot get lost.

Python turns SIGINT into ``KeyboardInterrupt`` in the main thread at the next bytecode; if
that happens inside a handler the interpreter runs for itself (logging's lock release after a
``fork``, a ``__del__``), the exception is printed as "Exception ignored" and dropped, and a
long sweep runs on.  :func:`install` (called by the command line) makes the handler also set
a flag that long loops check with :func:`requested` between units of work; :func:`deferred`
holds Ctrl-C back over code that must not be cut in two (forking a pool's workers).
"""

import signal
import threading
from contextlib import contextmanager

_flag = [False]


def _handler(signum, frame):
    _flag[0] = True
    signal.default_int_handler(signum, frame)


def install():
    """Make SIGINT set the flag of :func:`requested` before raising ``KeyboardInterrupt``.

    Returns the handler it replaced (give it to :func:`restore`), or None where nothing was
    installed: outside the main thread (Python allows handlers only there) or where SIGINT
    is ignored.
    """
    _flag[0] = False
    if threading.current_thread() is not threading.main_thread():
        return None
    old = signal.getsignal(signal.SIGINT)
    if old is signal.SIG_IGN or old is None:
        return None
    signal.signal(signal.SIGINT, _handler)
    return old


def restore(old) -> None:
    """Put back the handler :func:`install` returned (nothing if it returned None)."""
    if old is not None and threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, old)


def requested() -> bool:
    """True once Ctrl-C was pressed since :func:`install` (even if its exception was lost)."""
    return _flag[0]


@contextmanager
def deferred():
    """Hold Ctrl-C back for the block: inside, SIGINT is only noted; on leaving, a Ctrl-C
    that came raises ``KeyboardInterrupt``.

    The flag of :func:`requested` is not set (a library caller's next sweep must not see
    an old Ctrl-C).  For code that must not be cut in two, such as forking a pool's workers: a
    ``KeyboardInterrupt`` raised between ``fork()`` and the pool's bookkeeping leaves a
    worker nobody knows of, which holds the output pipes open after the program exits.
    Blocking the signal at the OS level is not enough: one the kernel handed to another
    thread just before is raised in the main thread at the next bytecode, wherever that is;
    here it finds this handler.  Outside the main thread, or with SIGINT ignored, a no-op.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.getsignal(signal.SIGINT)
    if old is signal.SIG_IGN or old is None:
        yield
        return
    came = [False]

    def hold(signum, frame):
        came[0] = True

    signal.signal(signal.SIGINT, hold)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)
    if came[0]:
        raise KeyboardInterrupt


__all__ = ["deferred", "install", "requested", "restore"]
