"""Reading the user's input files: one set of checks for every text file the toolkit reads.

Arm files, head files, study files, campaign manifests, import profiles, the sidecar
metadata of measured data and raw bench files are all read with :func:`read_text`, so a
wrong file gets the same clear error whatever kind of file it is:

* the path must be a ``str`` or ``os.PathLike``, not empty and without NUL characters
  (:func:`check_input_path`; ``TypeError``/``ValueError`` naming the argument);
* a missing file raises :class:`MissingFileError` (a ``FileNotFoundError`` *and* a
  ``ValueError``), naming the kind of file and its path;
* a folder, a pipe, a device or a socket is refused (:class:`InputFileError`): reading
  ``/dev/zero`` or a FIFO would never end;
* a file larger than ``max_bytes`` is refused with its size *before* it is read, and a
  compressed file (``.gz``, ``.xz``, ``.lzma``, ``.bz2``) is decompressed with the same limit on its
  decompressed size (a small archive can hold gigabytes);
* the text must be UTF-8; a byte-order mark (Windows editors write one) is skipped, and
  Windows line ends (CRLF) are read like Unix ones (TOML and CSV readers accept both); a
  binary file (NUL bytes) or another encoding is refused with the byte offset.

It sits in the lowest layer, beside :mod:`ppamsafety._validation`.
"""

from __future__ import annotations

import bz2
import gzip
import lzma
import os
import stat
from pathlib import Path

__all__ = ["InputFileError", "MissingFileError", "MAX_TEXT_BYTES", "check_input_path",
           "check_input_file", "read_bytes", "decode_text", "read_text"]

#: Largest text file (arm, head, study file, manifest, profile) read [bytes]: 64 MB, a
#: thousand times the largest such file the toolkit ships.
MAX_TEXT_BYTES = 64 * 2 ** 20

_OPENERS = {".gz": gzip.open, ".xz": lzma.open, ".lzma": lzma.open, ".bz2": bz2.open}


class InputFileError(ValueError):
    """An input file exists but cannot be read as what it should be."""


class MissingFileError(FileNotFoundError, ValueError):
    """An input file does not exist (a ``FileNotFoundError``; also a ``ValueError``, the
    convention of the toolkit's other input errors)."""


def check_input_path(name: str, path) -> Path:
    """Check that ``path`` names a file (a non-empty ``str`` or ``os.PathLike``); return it.

    Parameters
    ----------
    name : str
        How the argument is named in the error message (``"path"``, ``"--arm"``).
    path : str or os.PathLike
        The path.

    Raises
    ------
    TypeError
        ``path`` is not a ``str`` or ``os.PathLike`` (``bytes``, ``None``, a number ...).
    ValueError
        ``path`` is empty (``Path("")`` would silently mean the current folder) or holds a
        NUL character.
    """
    if isinstance(path, bool) or not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"{name} must be a path (str or os.PathLike), got "
                        f"{type(path).__name__} {path!r:.60}")
    text = os.fspath(path)
    if not isinstance(text, str):
        raise TypeError(f"{name} must be a path given as str, got {type(text).__name__}")
    if not text.strip():
        raise ValueError(f"{name} = {text!r} is an empty path; give the path of a file")
    if "\0" in text:
        raise ValueError(f"{name} = {text!r} holds a NUL character")
    return Path(text)


def check_input_file(path, *, what: str, name: str = "path") -> Path:
    """Check that ``path`` is an existing regular file; return it as a ``Path``.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str
        What the file is, for the messages (``"arm file"``, ``"study file"``).
    name : str
        The argument's name (for a path of the wrong type).

    Raises
    ------
    MissingFileError
        The file does not exist (a dangling symbolic link included).
    InputFileError
        It is a folder, a pipe, a device or a socket.
    """
    p = check_input_path(name, path)
    try:
        st = p.stat()
    except FileNotFoundError:
        raise MissingFileError(f"{what} '{p}' does not exist") from None
    except NotADirectoryError:
        raise MissingFileError(f"{what} '{p}' does not exist (a part of the path is a file, "
                               f"not a folder)") from None
    except OSError as exc:
        raise InputFileError(f"{what} '{p}' cannot be read ({exc.strerror or exc})") from None
    if stat.S_ISDIR(st.st_mode):
        raise InputFileError(f"{what} '{p}' is a folder, not a file")
    if not stat.S_ISREG(st.st_mode):
        raise InputFileError(f"{what} '{p}' is not a regular file (a device, a pipe or a "
                             f"socket); give the path of a file")
    return p


def _size_text(n: float) -> str:
    return f"{n / 2 ** 20:.3g} MB" if n < 2 ** 30 else f"{n / 2 ** 30:.3g} GB"


def read_bytes(path, *, what: str, name: str = "path", max_bytes: int = MAX_TEXT_BYTES,
               error=InputFileError, compressed: bool = False) -> tuple:
    """The bytes of an input file, checked as in the module docstring.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str
        What the file is (``"bench file"``), for the messages.
    name : str
        The argument's name.
    max_bytes : int
        Largest size accepted [bytes] (decompressed size for a compressed file).
    error : type
        Exception class of a file that is too large or unreadable (a ``ValueError``
        subclass such as the caller's own error type).
    compressed : bool
        Decompress ``.gz``, ``.xz`` and ``.bz2`` files.

    Returns
    -------
    (pathlib.Path, bytes)
    """
    p = check_input_file(path, what=what, name=name)
    opener = _OPENERS.get(p.suffix.lower()) if compressed else None
    size = p.stat().st_size
    if opener is None and size > max_bytes:
        raise error(f"{what} '{p}' holds {_size_text(size)}, more than the "
                    f"{_size_text(max_bytes)} a {what} may have: is it the right file?")
    try:
        if opener is None:
            raw = p.read_bytes()
        else:
            with opener(p, "rb") as fh:
                raw = fh.read(max_bytes + 1)
            if len(raw) > max_bytes:
                raise error(f"{what} '{p}' decompresses to more than {_size_text(max_bytes)}, "
                            f"the most a {what} may hold: is it the right file?")
    except (OSError, EOFError, lzma.LZMAError) as exc:
        raise error(f"{what} '{p}' cannot be read ({getattr(exc, 'strerror', None) or exc})") \
            from None
    return p, raw


def decode_text(raw: bytes, where: str, *, error=InputFileError) -> str:
    """UTF-8 text of ``raw`` (a leading byte-order mark skipped); binary or other encodings
    are refused with the byte offset.

    Parameters
    ----------
    raw : bytes
        The file's content.
    where : str
        The file, for the message.
    error : type
        Exception class raised.
    """
    if b"\0" in raw:
        k = raw.index(b"\0")
        raise error(f"{where}: a binary file (a NUL byte at offset {k}), not UTF-8 text")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        before = raw[max(0, exc.start - 20):exc.start]
        raise error(f"{where}: not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset "
                    f"{exc.start}, after {before!r}); re-save the file as UTF-8") from None
    return text


def read_text(path, *, what: str, name: str = "path", max_bytes: int = MAX_TEXT_BYTES,
              error=InputFileError, compressed: bool = False) -> tuple:
    """The UTF-8 text of an input file, checked as in the module docstring.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str
        What the file is (``"arm file"``, ``"study file"``), for the messages.
    name : str
        The argument's name.
    max_bytes : int
        Largest size accepted [bytes].
    error : type
        Exception class of a file that cannot be read as text (the caller's own
        ``ValueError`` subclass, e.g. the study file's).
    compressed : bool
        Decompress ``.gz``, ``.xz`` and ``.bz2`` files.

    Returns
    -------
    (pathlib.Path, str)
        The path and its text.
    """
    p, raw = read_bytes(path, what=what, name=name, max_bytes=max_bytes, error=error,
                        compressed=compressed)
    return p, decode_text(raw, str(p), error=error)
