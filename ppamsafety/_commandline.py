"""Running a command line safely: one parser style, one way errors become exit statuses.

:func:`run_guarded` is how every ``ppamsafety`` command and every section script
(``python studies/<section>.py``) turns errors into exit statuses, so that no user
error ends in a Python traceback:

0
    Success.
2
    Bad usage or input (``ppamsafety: error: ...`` on stderr).
1
    A failure that is not the user's; ``PPAMSAFETY_DEBUG=1`` shows the traceback.  A
    ``TypeError`` is the user's only when the library raised it on purpose
    (:func:`is_internal_error`): a call with a wrong keyword, an operation on the wrong type,
    a ``TypeError`` of numpy or the standard library are bugs of ppamsafety.
130
    Interrupted (Ctrl-C).

It sits in the lowest layer, beside :mod:`ppamsafety.output`, because commands of
every layer use it (``docs/architecture.md``).
"""

from __future__ import annotations

import argparse
import logging
import os
import re
import sys
import traceback
import warnings

from ._interrupt import install as install_interrupt, restore as restore_interrupt
from ._errors import InternalFailure, is_internal_error, mark_internal

EXIT_OK, EXIT_FAILURE, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130


#: Options taking several values; ``--q=-1 -80`` is split into ``--q -1 -80`` for them.
_MULTI_VALUE = ("--q", "--qd", "--stiffness")


#: Attribute of the parsed namespace that records the options given (removed after parsing).
_GIVEN = "_ppamsafety_given"


class _StoreOnce(argparse._StoreAction):
    """argparse's ``store``, refusing an option given twice (``--seed 1 ... --seed 2``).

    argparse keeps the last value silently; a repeated option is almost always an edited
    command line whose first value the user still believes in, so it is a usage error
    naming the option and both values.  (Options that may repeat use ``action="append"``.)
    """

    def __call__(self, parser, namespace, values, option_string=None):
        given = namespace.__dict__.setdefault(_GIVEN, {})
        if option_string is not None:
            if self.dest in given:
                first, before = given[self.dest]
                raise argparse.ArgumentError(
                    self, f"given twice ({first} {_shown(before)} and {option_string} "
                          f"{_shown(values)}); give it once")
            given[self.dest] = (option_string, values)
        super().__call__(parser, namespace, values, option_string)


def _shown(values) -> str:
    if isinstance(values, (list, tuple)):
        return " ".join(_shown(v) for v in values)
    return repr(values) if isinstance(values, str) and (not values or " " in values) \
        else str(values)


class Parser(argparse.ArgumentParser):
    """ArgumentParser that reads ``-1e5`` and ``-.5E-3`` as numbers, not as options, and
    refuses a single-valued option given twice.

    argparse (Python < 3.13) recognises negative numbers only without an
    exponent; this widens its number pattern (the same idea as Python 3.13's
    own, which accepts any ``-`` followed by a digit).  The parser has no
    option that looks like a number, so nothing is shadowed.  Every ``store``
    option is a :class:`_StoreOnce`: given twice, it is a usage error (exit 2).
    """

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", argparse.RawDescriptionHelpFormatter)
        super().__init__(*args, **kwargs)
        self.register("action", None, _StoreOnce)
        self.register("action", "store", _StoreOnce)
        self._negative_number_matcher = re.compile(
            r"^-(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$|^-(inf|infinity|nan)$", re.IGNORECASE)

    def error(self, message):
        """A usage error in the format of every other error: one line ``ppamsafety: error:
        ...`` on stderr (exit 2) naming the subcommand, with a pointer to its ``--help``
        (argparse would print the whole usage first)."""
        sub = self.prog.split(" ", 1)[1] + ": " if " " in self.prog else ""
        self.exit(EXIT_USAGE, f"ppamsafety: error: {sub}{_one_line(message)} (see "
                              f"'{self.prog} --help')\n")

    def parse_known_args(self, args=None, namespace=None):
        ns, rest = super().parse_known_args(args, namespace)
        ns.__dict__.pop(_GIVEN, None)
        return ns, rest


def _split_multi_value(argv: list[str]) -> list[str]:
    out = []
    for i, a in enumerate(argv):
        if a == "--":
            return out + argv[i:]
        opt, eq, val = a.partition("=")
        if eq and opt in _MULTI_VALUE:
            out += [opt, val]
        else:
            out.append(a)
    return out


def _error(msg: str) -> None:
    print(f"ppamsafety: error: {_one_line(msg)}", file=sys.stderr)


def _one_line(msg) -> str:
    return " ".join(str(msg).split())


class _LineHandler(logging.Handler):
    """What the library logs (e.g. which previous output is replaced) as ``ppamsafety: ...``."""

    def emit(self, record):
        try:
            print(f"ppamsafety: {_one_line(record.getMessage())}", file=sys.stderr)
        except (OSError, ValueError):
            pass


class _Warnings:
    """Show every warning of a command once, as ``ppamsafety: warning: ...`` (one line, no
    source line), instead of Python's ``file.py:12: UserWarning: ...`` and the code line."""

    def __init__(self):
        self.seen = set()

    def show(self, message, category, filename, lineno, file=None, line=None):
        text = _one_line(message)
        if text in self.seen:
            return
        self.seen.add(text)
        try:
            print(f"ppamsafety: warning: {text}", file=sys.stderr if file is None else file)
        except (OSError, ValueError):         # stderr closed: nothing to tell
            pass


def run_guarded(parser: argparse.ArgumentParser, func, argv=None) -> int:
    """Parse ``argv`` and run ``func(args)``, turning every error into an exit status.

    Usage errors print argparse's message and give 2 (``--help`` gives 0); a
    ``ValueError``, ``TypeError`` or ``OSError`` (bad input, including
    :class:`ppamsafety.output.OutputError`) prints ``ppamsafety: error: ...``
    and gives 2, and so does a ``MemoryError`` (a request too large for the machine:
    the library refuses the sizes it can estimate before allocating, this is the net);
    any other exception, and a ``TypeError`` that is a bug (:func:`is_internal_error`),
    prints one line asking to report it and gives 1.  No traceback unless the environment
    sets ``PPAMSAFETY_DEBUG=1``.
    Every warning raised while ``func`` runs is printed once as one line
    ``ppamsafety: warning: ...`` (no Python source line).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Parser of the command line.
    func : callable
        ``func(args) -> int``: runs the command on the parsed namespace and
        returns its exit status.
    argv : sequence of str, optional
        Arguments without the program name (default ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status (``func``'s, or 0, 1, 2 or the interrupt status as
        above).
    """
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = os.environ.get("PPAMSAFETY_DEBUG", "") not in ("", "0")
    try:
        args = parser.parse_args(_split_multi_value([str(a) for a in argv]))
    except SystemExit as exc:          # argparse: --help (0) or a usage error (2)
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    previous_sigint = install_interrupt()
    shown = _Warnings()
    log = logging.getLogger("ppamsafety")
    handler = _LineHandler()
    old_level = log.level
    log.addHandler(handler)
    log.setLevel(logging.INFO)
    try:
        with warnings.catch_warnings():
            warnings.showwarning = shown.show
            return func(args)
    except BrokenPipeError:            # e.g. `ppamsafety impact ... | head`: the reader left
        try:                           # early; nothing is wrong with the command or its input
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())   # no second error when Python flushes
        except (OSError, ValueError):
            pass
        return EXIT_OK
    except KeyboardInterrupt:
        print("ppamsafety: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except MemoryError:
        if debug:
            traceback.print_exc()
        _error("the request needs more memory than this machine can give (MemoryError); "
               "ask for less: a shorter duration, fewer cases or samples")
        return EXIT_USAGE
    except (ValueError, TypeError, OSError, argparse.ArgumentError,
            argparse.ArgumentTypeError) as exc:
        if debug:
            traceback.print_exc()
        if is_internal_error(exc):
            return _internal(exc)
        _error(str(exc) or type(exc).__name__)
        return EXIT_USAGE
    except Exception as exc:           # not the user's fault
        if debug:
            traceback.print_exc()
        return _internal(exc)
    finally:
        log.removeHandler(handler)
        log.setLevel(old_level)
        restore_interrupt(previous_sigint)


def _internal(exc: BaseException) -> int:
    what = str(exc) if isinstance(exc, InternalFailure) else f"{type(exc).__name__}: {exc}"
    _error(f"internal failure ({what}); please report this with the command line used "
           f"(PPAMSAFETY_DEBUG=1 shows the traceback)")
    return EXIT_FAILURE


__all__ = ["EXIT_OK", "EXIT_FAILURE", "EXIT_USAGE", "EXIT_INTERRUPTED", "Parser", "run_guarded",
           "InternalFailure", "is_internal_error", "mark_internal"]
