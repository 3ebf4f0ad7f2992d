"""Atomic file writes: a result file is either the old complete one or the new complete one.

Every file fdikit writes goes through :func:`atomic_path`: the content is written to a
temporary file in the destination folder, flushed and ``fsync``-ed, then renamed over the
destination with :func:`os.replace` (atomic on POSIX and Windows for a same-folder rename),
and the folder entry is synced.  A kill at any point leaves either the previous file or the
new one, never a truncated mix; on an exception the temporary file is removed.

Written by hand because the standard library has no atomic-replace writer and the
third-party ones (``atomicwrites``) are unmaintained.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from fdikit.errors import DataError

__all__ = ["atomic_path", "write_text", "write_bytes"]


def _fsync_dir(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:  # pragma: no cover - platforms without directory fds
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover
        pass
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, *, suffix: str = "") -> Iterator[Path]:
    """Yield a temporary path next to ``path``; on success it replaces ``path`` atomically.

    Parameters
    ----------
    path : str or PathLike
        Destination file.  Its folder is created when missing.
    suffix : str, optional
        Suffix of the temporary file (some writers look at it).

    Yields
    ------
    pathlib.Path
        Where the caller writes the complete content.  The caller may close the file it wrote;
        this function fsyncs it before the rename.

    Raises
    ------
    DataError
        When ``path`` is an existing folder, its folder cannot be created, or the temporary file
        cannot be created, synced or renamed (the previous file is then unchanged).  Exceptions
        raised by the caller's own writing propagate unchanged (the temporary file is removed).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> dest = pathlib.Path(tempfile.mkdtemp()) / "table.csv"
    >>> with atomic_path(dest, suffix=".csv") as tmp:
    ...     _ = tmp.write_text("a,b")
    >>> dest.read_text()
    'a,b'
    """
    path = Path(path)
    if path.is_dir():
        raise DataError(f"cannot write {path}: it is a folder; give a file name")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise DataError(f"cannot create the folder of {path}: {exc.strerror or exc}") from exc
    try:
        fd, tmp_name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix + ".tmp", dir=path.parent)
    except OSError as exc:
        raise DataError(f"cannot write {path}: {exc.strerror or exc} (is its folder writable?)") from exc
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        try:
            with open(tmp, "rb+") as fh:
                os.fsync(fh.fileno())
            os.replace(tmp, path)
        except OSError as exc:
            raise DataError(f"cannot write {path}: {exc.strerror or exc}; the previous file is unchanged") from exc
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise
    _fsync_dir(path.parent)


def write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (see :func:`atomic_path`); return the path.

    Parameters
    ----------
    path : str or PathLike
        Destination file; its folder is created when missing.
    data : bytes
        The complete new content.

    Returns
    -------
    pathlib.Path
        ``path``, which now holds exactly ``data``.

    Raises
    ------
    DataError
        As :func:`atomic_path`: the destination is a folder, or the file cannot be written (the previous file is
        then unchanged).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> out = write_bytes(pathlib.Path(tempfile.mkdtemp()) / "blob.bin", bytes([0, 1]))
    >>> list(out.read_bytes())
    [0, 1]
    """
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text(path: str | os.PathLike, text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically (see :func:`atomic_path`); return the path.

    Parameters
    ----------
    path : str or PathLike
        Destination file; its folder is created when missing.
    text : str
        The complete new content.
    encoding : str, optional
        Text encoding (UTF-8 by default).

    Returns
    -------
    pathlib.Path
        ``path``, which now holds exactly ``text``.

    Raises
    ------
    DataError
        As :func:`atomic_path`.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> write_text(pathlib.Path(tempfile.mkdtemp()) / "note.txt", "done").read_text()
    'done'
    """
    return write_bytes(path, text.encode(encoding))
