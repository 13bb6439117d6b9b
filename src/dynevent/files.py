"""Files named on a command line (or to an API that reads a path): read and written within bounds.

Every file dynevent reads for a user goes through :func:`read_bytes` (or :func:`read_text` and
:func:`read_json` above it): only a regular file is read (a FIFO, a device or a directory would
block or never end, and is named in one line instead), its size is bounded before it is read,
standard input is ``-`` where the caller allows it, and every failure, a path too long, a file
not there or not readable, text that is not UTF-8, JSON too deep, is one :class:`FileError`
naming the file.

Every file a command writes goes the same way: :func:`check_writable` tries its path before the
command's work starts (a path too long, a directory, a folder that does not exist, no permission:
one :class:`FileError`, the same as the write would give), and :func:`create_text` or
:func:`write_text` write it, whatever text it holds (a lone surrogate is escaped, not an error).
"""

from __future__ import annotations

import errno
import os
import stat
import sys
import tempfile
from typing import Any, BinaryIO, TextIO

from dynevent.errors import FileError
from dynevent.wire import _json

__all__ = [
    "MAX_FILE_BYTES",
    "check_writable",
    "create_directory",
    "create_text",
    "kind",
    "open_regular",
    "read_bytes",
    "read_json",
    "read_text",
    "write_text",
]

#: The most bytes a file is read to by default (a configuration, a description, a goal file).
MAX_FILE_BYTES = 16_000_000

_KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


def kind(mode: int) -> str:
    """What a file of ``mode`` (``os.stat``'s) is, when it is not a regular file: ``"a FIFO"``..."""
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def _reason(error: Exception) -> str:
    if isinstance(error, OSError):
        return error.strerror or type(error).__name__
    return "a path cannot hold a NUL character"  # the one ValueError os.open raises


def _bounded(stream: BinaryIO, what: str, path: str, limit: int) -> bytes:
    data = stream.read(limit + 1)
    if len(data) > limit:
        raise FileError(what, path, f"holds more than {limit:,} bytes")
    return data


def open_regular(path: str, what: str, *, limit: int | None = None) -> BinaryIO:
    """The regular file at ``path``, open for reading in binary (for a caller that streams it);
    raises :class:`FileError` naming ``what`` and the path for anything else, or for a file of
    more than ``limit`` bytes."""
    try:
        # O_NONBLOCK: opening a FIFO for reading does not wait for a writer; fstat then refuses it
        descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except (OSError, ValueError) as error:  # ValueError: a NUL in the path
        raise FileError(what, path, f"cannot be opened: {_reason(error)}") from None
    try:
        mode = os.fstat(descriptor)
        if not stat.S_ISREG(mode.st_mode):
            raise FileError(what, path, f"is {kind(mode.st_mode)}, not a regular file")
        if limit is not None and mode.st_size > limit:
            raise FileError(what, path, f"holds {mode.st_size:,} bytes, more than {limit:,}")
        os.set_blocking(descriptor, True)
        return os.fdopen(descriptor, "rb")
    except BaseException:
        os.close(descriptor)
        raise


def read_bytes(path: str, what: str, *, limit: int = MAX_FILE_BYTES, stdin: bool = False) -> bytes:
    """The bytes of the regular file at ``path`` (``-`` is standard input when ``stdin``), at most
    ``limit`` of them; raises :class:`FileError` naming ``what`` and the path otherwise."""
    if stdin and path == "-":
        return _bounded(sys.stdin.buffer, what, "standard input", limit)
    with open_regular(path, what, limit=limit) as stream:
        try:
            return _bounded(stream, what, path, limit)
        except OSError as error:
            raise FileError(what, path, f"cannot be read: {_reason(error)}") from None


def read_text(path: str, what: str, *, limit: int = MAX_FILE_BYTES, stdin: bool = False) -> str:
    """:func:`read_bytes`, decoded as UTF-8 (a file that is not is a :class:`FileError`)."""
    data = read_bytes(path, what, limit=limit, stdin=stdin)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise FileError(what, _shown(path, stdin), f"is not UTF-8 text (byte {error.start})") from None


def read_json(path: str, what: str, *, limit: int = MAX_FILE_BYTES, stdin: bool = False) -> Any:
    """:func:`read_text`, parsed as JSON strictly (nesting bounded, duplicate keys refused)."""
    text = read_text(path, what, limit=limit, stdin=stdin)
    try:
        return _json.parse(text)
    except _json.JsonProblem as problem:
        raise FileError(what, _shown(path, stdin), f"is not JSON dynevent reads: {problem}") from None


def _shown(path: str, stdin: bool) -> str:
    return "standard input" if stdin and path == "-" else path


def _unwritable(what: str, path: str, error: Exception) -> FileError:
    return FileError(what, path, f"cannot be written: {_reason(error)}")


def check_writable(path: str | None, what: str, *, directory: bool = False) -> None:
    """Raise :class:`FileError` naming ``what`` unless a command can write ``path`` (a file; with
    ``directory``, a directory that holds its files, made if it is not there): tried, before the
    command's work starts, as the write would try it, and nothing left behind.  An existing file is
    not changed; a FIFO or a device (``/dev/stdout``) is written as it comes.  None (an output the
    command was not asked for) is nothing to check."""
    if path is None:
        return
    try:
        if directory:
            _try_directory(path)
            return
        try:
            os.close(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0)))
        except FileExistsError:
            pass
        else:
            os.unlink(path)
            return
        # what is there, opened to write without truncating it; a FIFO without a reader yet is fine
        os.close(os.open(path, os.O_WRONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0)))
    except OSError as error:
        if error.errno != errno.ENXIO:
            raise _unwritable(what, path, error) from None
    except ValueError as error:  # a NUL in the path
        raise _unwritable(what, path, error) from None


def _try_directory(path: str) -> None:
    if _make_directory(path):
        os.rmdir(path)
        return
    descriptor, made = tempfile.mkstemp(dir=path, prefix=".dynevent-")  # a file can be made in it
    os.close(descriptor)
    os.unlink(made)


def _make_directory(path: str) -> bool:
    """Make the directory ``path``: True, or False when one is there already (OSError otherwise)."""
    try:
        os.mkdir(path)
    except FileExistsError:
        if not os.path.isdir(path):
            raise NotADirectoryError(errno.ENOTDIR, os.strerror(errno.ENOTDIR)) from None
        return False
    return True


def create_directory(path: str, what: str) -> None:
    """Make the directory ``path`` (one there already is used); raises :class:`FileError` naming
    ``what`` when it cannot be made."""
    try:
        _make_directory(path)
    except (OSError, ValueError) as error:
        raise _unwritable(what, path, error) from None


def create_text(path: str, what: str) -> TextIO:
    """``path`` opened to write UTF-8 text (a lone surrogate escaped as ``\\udXXX``, never an
    error); raises :class:`FileError` naming ``what`` when the path cannot be written."""
    try:
        return open(path, "w", encoding="utf-8", errors="backslashreplace")  # the caller's
    except (OSError, ValueError) as error:
        raise _unwritable(what, path, error) from None


def write_text(path: str, text: str, what: str) -> None:
    """Write ``text`` to ``path`` as UTF-8 (a lone surrogate escaped as ``\\udXXX``); raises
    :class:`FileError` naming ``what`` when the path cannot be written."""
    with create_text(path, what) as stream:
        try:
            stream.write(text)
        except OSError as error:  # a full disk
            raise _unwritable(what, path, error) from None
