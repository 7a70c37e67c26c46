"""Files, safely: check where a file may go, write it atomically, read JSON with clear errors.

Every file fohw writes (models, results, tables, outputs and figures) goes through
:func:`atomic_writer` (:func:`write_text`, :func:`save_figure`): all of it or nothing, so a failed
or interrupted save, or a full disk, never truncates an existing file.
"""

from __future__ import annotations

import contextlib
import json
import os
import stat
import tempfile

import numpy as np

from ..exceptions import DataFileError, ParameterError

__all__ = ["check_output_path", "check_input_file", "read_json", "write_json", "write_text",
           "atomic_writer", "save_figure", "first_non_finite"]


def check_output_path(path, what="the output") -> str:
    """Check, before any work, that a file can be written at ``path``; return it as a string.

    The check does what the save will do: it creates a temporary file in the target's folder and
    removes it, so a folder that only looks writable (``/proc``, ``/sys``, a read-only mount, a
    full quota) is refused before the run, not after it.

    Raises
    ------
    DataFileError
        ``path`` is a directory, a dangling symbolic link, an existing file that is not a
        regular file (a FIFO, a device, a socket: fohw never replaces one with a regular file),
        its folder does not exist, or no file can be created in the folder.
    """
    path = os.fspath(path)
    if isinstance(path, bytes):
        path = os.fsdecode(path)
    if os.path.isdir(path):
        raise DataFileError(f"{what} {path!r} is a directory; give a file name.")
    if os.path.islink(path) and not os.path.exists(path):
        raise DataFileError(f"{what} {path!r} is a symbolic link to {os.readlink(path)!r}, "
                            "which does not exist; fohw writes through a link, not over it: fix "
                            "the link or give another file name.")
    if os.path.exists(path) and not stat.S_ISREG(os.stat(path).st_mode):
        raise DataFileError(f"{what} {path!r} exists and is not a regular file ("
                            f"{_file_kind(os.stat(path).st_mode)}); fohw does not replace it: "
                            "give another file name.")
    folder = os.path.dirname(os.path.realpath(path))
    if not os.path.isdir(folder):
        raise DataFileError(f"{what} {path!r}: the folder {folder!r} does not exist.")
    try:
        fd, probe = tempfile.mkstemp(prefix=".fohw-check.", suffix=".tmp", dir=folder)
    except OSError as exc:
        raise DataFileError(f"{what} {path!r}: no file can be created in the folder {folder!r} "
                            f"({exc.strerror or exc}).") from None
    os.close(fd)
    os.unlink(probe)
    return path


def _file_kind(mode):
    for test, kind in ((stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return kind
    return "a special file"


def check_input_file(path, what="a data file") -> str:
    """``path`` as a string if it is a regular file (symbolic links followed), else a clear error.

    A directory, a FIFO, a device (``/dev/zero`` behind a symbolic link: a read that never ends)
    or a socket is refused before it is opened; a missing file is a ``FileNotFoundError``.

    Raises
    ------
    FileNotFoundError
        Nothing exists at ``path`` (a dangling symbolic link included).
    DataFileError
        ``path`` is not a regular file.
    """
    path = os.fspath(path)
    if isinstance(path, bytes):
        path = os.fsdecode(path)
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise FileNotFoundError(f"{what.removeprefix('a ')} not found: {path!r}") from None
    except OSError as exc:
        raise DataFileError(f"{path!r}: cannot be read ({exc.strerror or exc}).") from None
    if stat.S_ISREG(mode):
        return path
    link = f" (a symbolic link to {os.path.realpath(path)!r})" if os.path.islink(path) else ""
    if stat.S_ISDIR(mode):
        raise DataFileError(f"{path!r}{link} is a directory, not {what}.")
    raise DataFileError(f"{path!r}{link} is {_file_kind(mode)}, not a regular file; fohw reads "
                        f"{what} only from a regular file (a FIFO or a device may never end).")


def read_json(path) -> dict:
    """The JSON content of ``path``; a :class:`~fohw.DataFileError` saying why it cannot be read.

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    DataFileError
        ``path`` is a directory, not UTF-8, not valid JSON, or unreadable.
    """
    path = check_input_file(path, "a fohw JSON file")
    try:
        with open(path, encoding="utf-8") as fh:
            return json.load(fh)
    except json.JSONDecodeError as exc:
        raise DataFileError(f"{path} is not valid JSON: {exc}.") from None
    except UnicodeDecodeError:
        raise DataFileError(f"{path} is not UTF-8 text, so not a fohw JSON file.") from None
    except FileNotFoundError:
        raise
    except OSError as exc:
        raise DataFileError(f"{path}: cannot be read ({exc.strerror or exc}).") from None


def first_non_finite(obj, where=""):
    """``(place, value)`` of the first NaN or infinity in a JSON-ready object, or None.

    The place is a dotted path (``details.J_history``, ``past[1]``); an array written as
    ``{"shape": ..., "data": ...}`` is named itself, not its ``data``.
    """
    if isinstance(obj, float):
        return None if np.isfinite(obj) else (where or "the value", obj)
    if isinstance(obj, dict):
        items = obj.items()
        if set(obj) == {"shape", "data"}:           # an array: name it, not its 'data'
            items = [(None, obj["data"])]
    elif isinstance(obj, (list, tuple)):
        items = ((f"[{i}]", v) for i, v in enumerate(obj))
    else:
        return None
    for key, value in items:
        inner = where if key is None else (f"{where}.{key}" if where and not key.startswith("[")
                                           else f"{where}{key}")
        found = first_non_finite(value, inner)
        if found is not None:
            return found
    return None


def write_json(obj, path):
    """Write ``obj`` as JSON, atomically (see :func:`write_text`).

    Non-finite numbers are refused before anything is written (JSON has none).

    Raises
    ------
    ParameterError
        ``obj`` holds a NaN or an infinity (the message names where).
    DataFileError
        ``path`` cannot be written (:func:`check_output_path`).
    """
    path = check_output_path(path, "the JSON file")
    bad = first_non_finite(obj)
    if bad is not None:
        raise ParameterError(f"cannot save to {path}: field {bad[0]!r} is {bad[1]!r}, and JSON "
                             "holds finite numbers only; nothing was written (an existing file "
                             "is unchanged).")
    write_text(json.dumps(obj, indent=1, allow_nan=False) + "\n", path)


def write_text(text, path):
    """Write ``text`` to ``path`` atomically: all of it, or nothing (see :func:`atomic_writer`)."""
    with atomic_writer(path, "w") as fh:
        fh.write(text)


def save_figure(fig, path, **savefig_kwargs):
    """Write a Matplotlib figure to ``path`` atomically (see :func:`atomic_writer`).

    The format comes from the extension, as :meth:`~matplotlib.figure.Figure.savefig` would
    choose it; a full disk or an interrupt leaves an existing figure byte for byte.
    """
    path = os.fspath(path)
    fmt = savefig_kwargs.pop("format", None) or os.path.splitext(path)[1].lstrip(".").lower()
    with atomic_writer(path, "wb") as fh:
        fig.savefig(fh, format=fmt or None, **savefig_kwargs)


@contextlib.contextmanager
def atomic_writer(path, mode="w"):
    """A file object whose content replaces ``path`` only if the whole ``with`` block succeeds.

    The content goes to a temporary file in the same folder, flushed to disk, which then replaces
    ``path`` in one step (:func:`os.replace`), so an interrupted or failed save never truncates
    a file: an existing one survives byte for byte, and the temporary file is removed. A
    symbolic link is written through (its target is replaced, the link kept); a read-only file
    and a file that is not a regular file (a FIFO, a device) are refused
    (:func:`check_output_path`). Errors name ``path``, never the temporary file.
    """
    path = check_output_path(path, "the output file")
    path = os.path.realpath(path)             # write through a symbolic link, not over it
    if os.path.exists(path) and not os.access(path, os.W_OK):
        raise DataFileError(f"{path!r} is read-only; fohw does not replace it.")
    folder, name = os.path.split(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{name}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, mode, **({} if "b" in mode else {"encoding": "utf-8"})) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        if os.path.exists(path):                    # keep the permissions the file had
            os.chmod(tmp, os.stat(path).st_mode & 0o7777)
        else:
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except OSError as exc:
        _remove(tmp)
        if exc.filename == tmp or exc.filename2 == tmp or exc.filename is None:
            raise OSError(exc.errno, exc.strerror or str(exc), path) from None
        raise
    except BaseException:
        _remove(tmp)
        raise


def _remove(tmp):
    with contextlib.suppress(OSError):
        os.unlink(tmp)
