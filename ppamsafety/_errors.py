"""Bugs and bad input told apart: which exceptions are the user's, which are ppamsafety's.

Every command turns a ``ValueError``/``TypeError``/``OSError`` into ``ppamsafety: error: ...``
(exit 2, the user's input) and anything else into an internal failure (exit 1,
:mod:`ppamsafety._commandline`).  A ``TypeError`` is ambiguous: the library raises it on
purpose for an argument of the wrong kind (:class:`ppamsafety._validation.InvalidTypeError`
names it), but the interpreter raises it too for a call with a wrong keyword or an operation
on the wrong type, which is a bug.  :func:`is_internal_error` tells them apart from the
traceback; :func:`mark_internal` keeps the answer across a worker process, whose exception
reaches the parent without its traceback.  Bottom layer: the command line, the sweep engine
and the report use it.
"""

from __future__ import annotations

import dis
import os

#: The package's source folder: a ``raise`` statement in a file below it is the library
#: refusing an input on purpose (:func:`is_internal_error`).
_PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__)) + os.sep
_RAISE_OPS = frozenset({"RAISE_VARARGS", "RERAISE"})


class InternalFailure(RuntimeError):
    """A bug of ppamsafety met in a worker process (its message names the original error).

    A worker's exception reaches the parent without its traceback, which
    :func:`is_internal_error` reads: :func:`mark_internal` turns it into this class in the
    worker, and :func:`ppamsafety._commandline.run_guarded` reports it as an internal failure
    (exit 1).
    """


def is_internal_error(exc: BaseException) -> bool:
    """True if ``exc`` is a bug of ppamsafety, not bad input.

    Only ``TypeError`` needs a look: the library refuses a wrong type with a ``raise``
    statement of its own (:mod:`ppamsafety._validation` names the argument), while a call
    with an unexpected keyword, ``1 + "a"`` or a ``TypeError`` raised inside numpy, the
    standard library or ``inspect`` (``got an unexpected keyword argument 'head'``) is
    raised by the interpreter or by code that never saw the user's input.  The innermost
    frame of the traceback tells them apart: a ``raise`` instruction in a file of the package.

    Parameters
    ----------
    exc : BaseException
        A raised exception (with its traceback).

    Returns
    -------
    bool
        True for an :class:`InternalFailure` and for a ``TypeError`` not raised by a
        ``raise`` statement of ppamsafety; False otherwise (and for an exception without a
        traceback: nothing to tell).
    """
    if isinstance(exc, InternalFailure):
        return True
    if not isinstance(exc, TypeError) or exc.__traceback__ is None:
        return False
    tb = exc.__traceback__
    while tb.tb_next is not None:
        tb = tb.tb_next
    code = tb.tb_frame.f_code
    if not os.path.abspath(code.co_filename).startswith(_PACKAGE_DIR):
        return True
    op = next((i.opname for i in dis.get_instructions(code) if i.offset == tb.tb_lasti), "")
    return op not in _RAISE_OPS


def mark_internal(exc: BaseException, where: str) -> BaseException:
    """``exc``, or an :class:`InternalFailure` naming it if it is a bug (for worker processes).

    Parameters
    ----------
    exc : BaseException
        An exception caught in a worker.
    where : str
        What the worker was doing (e.g. ``"report section 'design'"``).

    Returns
    -------
    BaseException
        Raise it (``raise mark_internal(exc, where) from exc``).
    """
    if is_internal_error(exc) and not isinstance(exc, InternalFailure):
        return InternalFailure(f"{where}: {type(exc).__name__}: {exc}")
    return exc


__all__ = ["InternalFailure", "is_internal_error", "mark_internal"]
