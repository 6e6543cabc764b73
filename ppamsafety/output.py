"""Safe output: what the toolkit writes never deletes or overwrites a user's file.

Every writer of the package (``ppamsafety report``, the study scripts,
``ppamsafety impact --history``) goes through this module.

Output folders (:class:`OutputFolder`)
    * A missing folder is created; an empty folder is used.
    * A non-empty folder is used only if it is a previous ppamsafety output,
      recognised by the marker file ``.ppamsafety-output`` (JSON: ``tool``,
      ``version``, ``kind`` such as ``"report"``, and ``files``, the files the
      toolkit wrote there), and only when the caller asks for it explicitly
      (``--overwrite`` on the command line, ``overwrite=True`` in Python).
    * A folder that holds any file the marker does not list ("foreign" files)
      is refused, with or without the flag: those files are never touched.
    * A non-empty folder without a marker, or with a marker that is not valid,
      is refused.
    * The toolkit writes into a staging folder inside the target; only when
      everything succeeded are the files moved into place with
      :func:`os.replace` (atomic per file), so a failed run leaves the previous
      output untouched.  When replacing (``clean=True``), previous toolkit
      files that the new run did not write are removed -- only files the marker
      lists, and only folders that became empty.

Work folders (:meth:`OutputFolder.workdir`)
    A sub-folder the toolkit fills *during* a run (a sweep's cache of
    finished cases), so that an interrupted run can resume.  The marker lists
    it under ``dirs`` before anything is written into it; every file below a
    listed folder counts as written by the toolkit.  Work folders are not
    staged and are not removed when the output is replaced, except by an
    explicit :meth:`OutputFolder.workdir` call with ``fresh=True``.

Single files (:func:`atomic_write`)
    An existing file is an error unless ``overwrite=True`` (``--overwrite``);
    the content is written to a temporary file in the same folder and moved
    into place with :func:`os.replace`.
"""

from __future__ import annotations

import json
import logging
import os
import secrets
import shutil
import tempfile
import warnings
from pathlib import Path, PurePosixPath

from ._version import __version__

MARKER = ".ppamsafety-output"
"""Name of the marker file of a ppamsafety output folder."""

_STAGING_PREFIX = ".ppamsafety-staging-"
_LOG = logging.getLogger("ppamsafety.output")
_FLAG = "--overwrite (overwrite=True in Python)"


class OutputError(ValueError):
    """An output folder or file cannot be written without losing user data."""


def _few(items, n: int = 5) -> str:
    items = list(items)
    more = f" and {len(items) - n} more" if len(items) > n else ""
    return ", ".join(repr(i) for i in items[:n]) + more


def _as_path(name: str, value) -> Path:
    if isinstance(value, bool) or not isinstance(value, (str, os.PathLike)):
        raise TypeError(f"{name} must be a path (str or os.PathLike), got "
                        f"{type(value).__name__} {value!r}")
    text = os.fspath(value)
    if not isinstance(text, str):
        raise TypeError(f"{name} must be a path given as str, got {type(text).__name__}")
    if not text.strip():
        raise ValueError(f"{name} must be a non-empty path, got {text!r}")
    if "\0" in text:
        raise ValueError(f"{name} = {text!r} holds a NUL character")
    return Path(text)


def check_output_path(name: str, value) -> Path:
    """Check that ``value`` is a path (``str`` or ``os.PathLike``, not empty); return it.

    ``Path("")`` is the current folder: an empty output path is refused, never taken
    for ``.``.

    Parameters
    ----------
    name : str
        The argument's name, for the message.
    value : str or os.PathLike
        The path.
    """
    return _as_path(name, value)


def _valid_relpath(f) -> bool:
    if not isinstance(f, str) or not f or f == MARKER:
        return False
    p = PurePosixPath(f)
    return not p.is_absolute() and ".." not in p.parts and "\\" not in f


def read_marker(folder) -> dict | None:
    """The marker of ``folder`` as a dict, or None if it is missing or not valid.

    Valid means: a JSON object with ``tool == "ppamsafety"``, a string ``kind``
    and ``files``, a list of relative paths (``/``-separated, no ``..``), and
    optionally ``dirs``, a list of such paths: work folders whose files are
    all the toolkit's.

    Parameters
    ----------
    folder : path-like
        Folder whose marker file (``MARKER``) is read; need not exist.
    """
    f = Path(folder) / MARKER
    try:
        data = json.loads(f.read_text(encoding="utf-8"))
    except (OSError, ValueError, UnicodeDecodeError):
        return None
    if not (isinstance(data, dict) and data.get("tool") == "ppamsafety"
            and isinstance(data.get("kind"), str) and isinstance(data.get("files"), list)
            and all(_valid_relpath(x) for x in data["files"])
            and isinstance(data.get("dirs", []), list)
            and all(_valid_relpath(x) for x in data.get("dirs", []))):
        return None
    return data


def _under(entry: str, dirs) -> bool:
    """Whether the relative path ``entry`` lies inside one of the folders ``dirs``."""
    return any(entry.startswith(d.rstrip("/") + "/") for d in dirs)


def _entries(folder: Path, exclude: str | None = None) -> list[str]:
    """Relative paths of everything in ``folder`` that is not a directory (recursively).

    Symbolic links to folders count as entries (they are not followed); empty
    sub-folders are not listed.
    """
    out = []
    for root, dirs, files in os.walk(folder, followlinks=False):
        rel = Path(root).relative_to(folder)
        if exclude is not None and rel == Path("."):
            dirs[:] = [d for d in dirs if d != exclude]
        for d in list(dirs):
            if os.path.islink(os.path.join(root, d)):
                out.append((rel / d).as_posix())
                dirs.remove(d)
        out.extend((rel / f).as_posix() for f in files)
    return sorted(out)


def inspect_output_folder(folder, *, overwrite: bool = False, kind: str | None = None,
                          kinds=None, replace_kind: bool = False,
                          _exclude: str | None = None) -> dict:
    """Check that ``folder`` may receive toolkit output; raise :class:`OutputError` if not.

    Parameters
    ----------
    folder : path-like
        Output folder (need not exist).
    overwrite : bool
        Whether the user asked to replace a previous ppamsafety output.
    kind : str, optional
        The kind of output about to be written (``"sweep"``, ``"diagnose"`` ...).  A previous
        output of another kind is refused, even with ``overwrite``, unless ``replace_kind``
        (a diagnosis is not replaced by a sweep by accident).  None: any kind.
    kinds : iterable of str, optional
        The kinds of previous output this one may replace (default: ``kind`` alone).
    replace_kind : bool
        Allow replacing a previous output of another kind (``--replace-other-kind``).
    _exclude : str, optional
        Internal: name of a top-level sub-folder that is ignored when listing
        the folder's contents (:class:`OutputFolder` passes its own staging
        folder).  Default None: nothing is ignored.

    Returns
    -------
    dict
        ``{"files": set of toolkit files present (work folders included),
        "kind": str or None, "dirs": set of work folders}``.
    """
    p = _as_path("outdir", folder)
    if p.exists() and not p.is_dir():
        raise OutputError(f"output folder '{p}' exists and is not a folder")
    if not p.exists():
        return {"files": set(), "kind": None, "dirs": set()}
    entries = _entries(p, exclude=_exclude)
    stale = sorted({e.split("/", 1)[0] for e in entries if e.startswith(_STAGING_PREFIX)})
    if stale:
        # staging folders of an interrupted run (killed before it could clean up): ours by
        # name, never user data; left in place (nothing is deleted), and not a reason to
        # refuse the folder
        entries = [e for e in entries if e.split("/", 1)[0] not in stale]
        warnings.warn(f"output folder '{p}' holds {len(stale)} staging folder(s) of an "
                      f"interrupted ppamsafety run ({_few(stale, 3)}); they are ignored and "
                      f"left in place, delete them when no run is using this folder",
                      UserWarning, stacklevel=3)
    if not entries:
        return {"files": set(), "kind": None, "dirs": set()}
    marker = read_marker(p)
    if marker is None:
        why = ("its marker file %s is not valid" % MARKER if (p / MARKER).exists()
               else "it has no marker file %s" % MARKER)
        raise OutputError(
            f"output folder '{p}' is not empty and {why}, so it is not a ppamsafety output "
            f"folder (it holds e.g. {_few(entries, 3)}); ppamsafety never deletes or overwrites "
            f"files it did not write: choose a new or empty folder")
    listed = set(marker["files"])
    dirs = set(marker.get("dirs", []))
    listed |= {e for e in entries if _under(e, dirs)}
    foreign = [e for e in entries if e not in listed and e != MARKER]
    if foreign:
        raise OutputError(
            f"output folder '{p}' holds {len(foreign)} file(s) ppamsafety did not write: "
            f"{_few(foreign)}; they are never deleted or overwritten, so the folder is not "
            f"used (not even with --overwrite): move them away or choose another folder")
    present = listed & set(entries)
    if entries == [MARKER] and not present:
        return {"files": set(), "kind": marker["kind"], "dirs": dirs}   # nothing but a marker
    allowed = set(kinds) if kinds is not None else ({kind} if kind is not None else None)
    if allowed is not None and marker["kind"] not in allowed and not replace_kind:
        raise OutputError(
            f"output folder '{p}' holds a previous ppamsafety {marker['kind']} output "
            f"({len(present)} files: {_few(sorted(present), 4)}), not a {kind}; "
            f"{'--overwrite' if overwrite else _FLAG} replaces only a previous {kind}: choose "
            f"another folder, or pass --replace-other-kind (replace_kind=True) to replace the "
            f"{marker['kind']}")
    if not overwrite:
        raise OutputError(
            f"output folder '{p}' holds a previous ppamsafety {marker['kind']} "
            f"({len(present)} files); pass {_FLAG} to replace it, or choose another folder")
    return {"files": present, "kind": marker["kind"], "dirs": dirs}


def _write_marker(folder: Path, kind: str, files, dirs=()) -> None:
    dirs = sorted(set(dirs))
    data = {"tool": "ppamsafety", "version": __version__, "kind": kind,
            "files": sorted(f for f in set(files) if not _under(f, dirs))}
    if dirs:
        data["dirs"] = dirs
    atomic_write(folder / MARKER, lambda t: t.write_text(json.dumps(data, indent=1) + "\n",
                                                         encoding="utf-8"),
                 overwrite=True)


class OutputFolder:
    """Context manager that writes a folder of results without losing user data.

    ``with OutputFolder(outdir, kind="report", overwrite=flag) as staging:``
    checks ``outdir`` (see the module docstring), creates it if missing and
    yields a staging folder inside it; write every file into ``staging``.  On a
    normal exit the files are moved into ``outdir`` and the marker is updated;
    on an exception ``outdir`` is left as it was (only the staging folder, which
    this object created, is removed).

    Parameters
    ----------
    outdir : path-like
        Output folder.
    kind : str
        What is written (``"report"``, ``"study"``), recorded in the marker.
    overwrite : bool
        Allow replacing a previous ppamsafety output in ``outdir``.
    clean : bool
        True: the new output replaces the previous one (previous toolkit files
        not written again are removed).  False: the new files are added to the
        previous output, replacing only files of the same name.
    kinds : iterable of str, optional
        Kinds of previous output this one may replace or update (default: ``kind``
        alone); a previous output of another kind is refused even with ``overwrite``.
    replace_kind : bool
        Allow replacing a previous output of any kind (``--replace-other-kind``).

    What is replaced is logged (logger ``ppamsafety.output``, level INFO; the command line
    prints it) before anything is written.
    """

    def __init__(self, outdir, *, kind: str, overwrite: bool = False, clean: bool = True,
                 kinds=None, replace_kind: bool = False):
        self.path = _as_path("outdir", outdir)
        if not isinstance(kind, str) or not kind:
            raise ValueError(f"kind must be a non-empty str, got {kind!r}")
        for nm, v in (("overwrite", overwrite), ("clean", clean), ("replace_kind", replace_kind)):
            if not isinstance(v, bool):
                raise TypeError(f"{nm} must be True or False, got {type(v).__name__} {v!r}")
        self.kind, self.overwrite, self.clean = kind, overwrite, clean
        self.kinds = None if kinds is None else tuple(kinds)
        self.replace_kind = replace_kind
        self.staging: Path | None = None
        self.written: list[str] = []
        self._dirs: set[str] = set()

    def __enter__(self) -> Path:
        self._prev = inspect_output_folder(self.path, overwrite=self.overwrite, kind=self.kind,
                                           kinds=self.kinds, replace_kind=self.replace_kind)
        if self._prev["files"]:
            verb = "replacing" if self.clean else "updating"
            _LOG.info(f"{verb} the previous ppamsafety {self._prev['kind']} output in "
                      f"'{self.path}' ({len(self._prev['files'])} files: "
                      f"{_few(sorted(self._prev['files']), 6)})")
        self._created = not self.path.exists()
        try:
            self.path.mkdir(parents=True, exist_ok=True)
            self.staging = Path(tempfile.mkdtemp(prefix=_STAGING_PREFIX, dir=self.path))
        except PermissionError as exc:
            raise OutputError(_not_writable("output folder", self.path, exc)) from None
        return self.staging

    def workdir(self, name: str, *, fresh: bool = False) -> Path:
        """A work folder ``outdir/name`` that is filled during the run (not staged).

        Call it inside the ``with`` block.  The marker is updated to list the
        folder (under ``dirs``) *before* it is returned, so files written into
        it count as the toolkit's even if the process is killed before the
        block ends; a later run with the same folder finds and may reuse them.

        Parameters
        ----------
        name : str
            Relative folder name (``/``-separated, no ``..``), e.g. ``"cache"``.
        fresh : bool
            Remove the files a previous run left in it first (only the
            toolkit's: the folder must already be a listed work folder, or
            be empty or missing).

        Returns
        -------
        pathlib.Path
            The work folder (created if missing).
        """
        if self.staging is None:
            raise RuntimeError("OutputFolder.workdir() must be called inside the with block")
        if not _valid_relpath(name) or name.startswith(_STAGING_PREFIX):
            raise ValueError(f"work folder name = {name!r} must be a relative path without "
                             f"'..' (e.g. 'cache')")
        d = self.path / name
        if d.exists() and not d.is_dir():
            raise OutputError(f"work folder '{d}' exists and is not a folder")
        prev = inspect_output_folder(self.path, overwrite=True, _exclude=self.staging.name)
        if fresh:
            for f in sorted(prev["files"]):
                if _under(f, [name]):
                    _remove_listed(self.path, f)
        self._dirs.add(name)
        kind = self.kind if self.clean or prev["kind"] is None else prev["kind"]
        _write_marker(self.path, kind, {f for f in prev["files"] if not _under(f, [name])},
                      prev["dirs"] | self._dirs)
        d.mkdir(parents=True, exist_ok=True)
        return d

    def __exit__(self, exc_type, exc, tb) -> bool:
        try:
            if exc_type is None:
                self._commit()
        finally:
            shutil.rmtree(self.staging, ignore_errors=True)   # our own temporary folder
            if exc_type is not None and self._created:
                # a run that failed in a folder it created leaves nothing behind: its work
                # folders if still empty, then the marker if nothing else is there
                for d in sorted(self._dirs, reverse=True):
                    try:
                        (self.path / d).rmdir()               # only if still empty
                    except OSError:
                        pass
                try:
                    if [e.name for e in self.path.iterdir()] == [MARKER]:
                        (self.path / MARKER).unlink()
                    self.path.rmdir()                         # only if still empty
                except OSError:
                    pass
        return False

    def _commit(self) -> None:
        # check again: a user may have put files into the folder meanwhile
        # (files in this run's work folders are ours: they need no --overwrite)
        prev = inspect_output_folder(self.path, overwrite=self.overwrite or bool(self._dirs),
                                     _exclude=self.staging.name)
        new = _entries(self.staging)
        kind = self.kind if self.clean or prev["kind"] is None else prev["kind"]
        dirs = self._dirs | (set() if self.clean else prev["dirs"])
        work = {f for f in prev["files"] if _under(f, self._dirs)}
        # the marker lists every toolkit file before any is moved, so an interrupted
        # commit never leaves files that a later run would take for the user's
        _write_marker(self.path, kind, prev["files"] | set(new), prev["dirs"] | self._dirs)
        for f in new:
            dst = self.path / f
            dst.parent.mkdir(parents=True, exist_ok=True)
            os.replace(self.staging / f, dst)
        final = set(new) | work                 # this run's work folders are kept
        if self.clean:
            for f in sorted(prev["files"] - final):
                _remove_listed(self.path, f)
        else:
            final |= prev["files"]
        _write_marker(self.path, kind, final, dirs)
        self.written = sorted(final)


def _not_writable(what: str, path: Path, exc: OSError) -> str:
    """Message for a target that cannot be written: the user's path, never a temporary file."""
    folder = path if what == "output folder" else (path.parent if str(path.parent) else Path("."))
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    return (f"{what} '{path}' cannot be written: folder '{folder}' is read-only or not "
            f"writable by this user ({exc.strerror or exc}); choose another folder or change "
            f"its permissions")


def _remove_listed(folder: Path, rel: str) -> None:
    """Remove one toolkit-written file, then its parent folders if they became empty."""
    p = folder / rel
    try:
        p.unlink()
    except FileNotFoundError:
        return
    parent = p.parent
    while parent != folder and folder in parent.parents:
        try:
            parent.rmdir()
        except OSError:
            break
        parent = parent.parent


def check_new_file(path, *, overwrite: bool = False, name: str = "output file") -> Path:
    """Check that a single output file may be written; return it as a Path.

    Raises :class:`OutputError` if the file exists and ``overwrite`` is False,
    if it is a folder, or if its folder does not exist.

    Parameters
    ----------
    path : path-like
        The file to be written.
    overwrite : bool
        Allow replacing an existing file (default False).
    name : str
        What the file is, for the error messages (default ``"output file"``).

    Raises
    ------
    TypeError
        If ``path`` is not a str/os.PathLike or ``overwrite`` is not a bool.
    ValueError
        If ``path`` is empty.
    OutputError
        As above.
    """
    p = _as_path(name, path)
    if not isinstance(overwrite, bool):
        raise TypeError(f"overwrite must be True or False, got {overwrite!r}")
    text = os.fspath(path)
    if os.path.basename(text) in ("", ".", ".."):          # "x/", ".", "x/..": a folder
        raise OutputError(f"{name} '{text}' names a folder, not a file; give the name of a "
                          f"file (e.g. '{text.rstrip('/' + os.sep) or '.'}/x.csv')")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        up = next((a for a in [parent, *parent.parents] if a.exists()), None)
        why = (f"'{up}' is a file, not a folder" if up is not None and not up.is_dir()
               else f"folder '{parent}' does not exist")
        raise OutputError(f"{name} '{p}': {why}")
    if p.is_dir():
        raise OutputError(f"{name} '{p}' is a folder")
    if p.exists() and not p.is_file():
        raise OutputError(f"{name} '{p}' exists and is not a regular file (a device, a pipe or "
                          f"a socket); it is never replaced, not even with --overwrite")
    marker = read_marker(parent) if p.name != MARKER else None
    if marker is not None:
        raise OutputError(f"{name} '{p}': folder '{parent}' is a ppamsafety "
                          f"{marker['kind']} output folder; a file written there would become "
                          f"a foreign file of that output: choose another folder")
    if (p.exists() or p.is_symlink()) and not overwrite:
        raise OutputError(f"{name} '{p}' already exists; ppamsafety does not overwrite files "
                          f"unless asked: pass {_FLAG} or choose another name")
    return p


def atomic_write(path, write, *, overwrite: bool = False, name: str = "output file") -> Path:
    """Write one file atomically, never replacing an existing file unless asked.

    Parameters
    ----------
    path : path-like
        Destination file; its folder must exist.
    write : callable
        ``write(tmp_path)`` writes the whole content to ``tmp_path`` (a new
        file in the same folder).
    overwrite : bool
        Replace an existing file.
    name : str
        How the file is named in error messages (e.g. ``"--history"``).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    p = check_new_file(path, overwrite=overwrite, name=name)
    tmp = p.with_name(f".{p.name}.{secrets.token_hex(4)}.tmp")
    try:
        open(tmp, "x").close()            # new file with the user's umask, never clobbers
    except PermissionError as exc:
        raise OutputError(_not_writable(name, p, exc)) from None
    try:
        write(tmp)
        if overwrite:
            os.replace(tmp, p)
        else:
            try:
                os.link(tmp, p)           # atomic and fails if the file appeared meanwhile
            except FileExistsError:
                raise OutputError(f"{name} '{p}' appeared while it was being written; "
                                  f"it was left untouched") from None
            except OSError:               # file system without hard links
                check_new_file(p, overwrite=False, name=name)
                os.replace(tmp, p)
    finally:
        if os.path.lexists(tmp):
            os.unlink(tmp)
    return p


__all__ = ["MARKER", "OutputError", "OutputFolder", "atomic_write", "check_new_file",
           "check_output_path",
           "inspect_output_folder", "read_marker"]
