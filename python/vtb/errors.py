"""Exceptions raised by vtb.

Every invalid input raises :class:`ConfigError` naming the offending field (a dotted path such
as ``vehicles[0].m_c``) and its value; numerical failures raise :class:`ConvergenceError`
(contact iteration) or :class:`SolverError`. All derive from :class:`VtbError`.
"""

from __future__ import annotations


class VtbError(Exception):
    """Base class of all vtb errors."""


class ConfigError(VtbError, ValueError):
    """A configuration field has an invalid value.

    Attributes: ``field`` (dotted path), ``value`` (as text) and ``reason``.
    """

    def __init__(self, message: str, field: str | None = None, value: str | None = None, reason: str | None = None):
        super().__init__(message)
        self.field = field
        self.value = value
        self.reason = reason

    def __reduce__(self):
        return (type(self), (self.args[0], self.field, self.value, self.reason))


class StaleFileError(ConfigError):
    """A study's journal or checkpoint was written for another configuration (another
    version of vtb, other settings). ``path`` is the file. ``--force`` on ``vtb reproduce`` and
    ``vtb study robust`` sets such files aside."""

    def __init__(self, message: str, field: str | None = None, value: str | None = None, reason: str | None = None, path: str | None = None):
        super().__init__(message, field, value, reason)
        self.path = path

    def __reduce__(self):
        return (type(self), (self.args[0], self.field, self.value, self.reason, self.path))


def config_error(field: str, value, reason: str) -> ConfigError:
    """A :class:`ConfigError` with the message format of the Rust core."""
    return ConfigError(f"invalid config field `{field}` = {value!r}: {reason}", field, repr(value), reason)


def stale_file_error(field: str, path, reason: str) -> StaleFileError:
    """A :class:`StaleFileError` for the file ``path`` given as ``field``."""
    return StaleFileError(f"invalid config field `{field}` = {str(path)!r}: {reason}", field, repr(str(path)), reason, str(path))


class ConvergenceError(VtbError, RuntimeError):
    """The wheel–rail contact iteration did not converge.

    Attributes: ``time`` (s), ``step``, ``residual`` (N) and ``iterations``.
    """

    def __init__(self, message: str, time: float = float("nan"), step: int = -1, residual: float = float("nan"), iterations: int = 0):
        super().__init__(message)
        self.time = time
        self.step = step
        self.residual = residual
        self.iterations = iterations

    def __reduce__(self):
        return (type(self), (self.args[0], self.time, self.step, self.residual, self.iterations))


class SolverError(VtbError, RuntimeError):
    """A numerical failure that valid input should not produce (e.g. an unsupported structure)."""


class OutputError(VtbError, OSError):
    """A file vtb writes could not be written (disk full, no permission, a read-only or missing
    folder). ``path`` is the file, ``field`` the argument that named it (``out``,
    ``checkpoint``), ``reason`` the cause as the system gave it and ``errno`` its number."""

    def __init__(self, message: str, field: str | None = None, path: str | None = None, reason: str | None = None, errno: int | None = None):
        VtbError.__init__(self, message)
        self.field = field
        self.path = path
        self.reason = reason
        self.errno = errno

    def __str__(self) -> str:
        return self.args[0]

    def __reduce__(self):
        return (type(self), (self.args[0], self.field, self.path, self.reason, self.errno))


def output_error(field: str, path, err: OSError) -> OutputError:
    """An :class:`OutputError` for the OSError ``err`` met writing ``path`` (named by ``field``)."""
    import errno as _errno
    import os as _os

    cause = {_errno.ENOSPC: "the disk is full", _errno.EDQUOT: "the disk quota is exceeded",
             _errno.EACCES: "permission denied", _errno.EPERM: "permission denied",
             _errno.EROFS: "the file system is read-only"}.get(err.errno) or (err.strerror or str(err))
    reason = f"{cause} ({_errno.errorcode.get(err.errno, err.errno)})" if err.errno else cause
    return OutputError(f"cannot write `{field}` = {_os.fspath(path)!r}: {reason}", field, _os.fspath(path), reason, err.errno)


def writing(field: str, path):
    """A context that turns an OSError met writing ``path`` into an :class:`OutputError`."""
    import contextlib

    @contextlib.contextmanager
    def guard():
        try:
            yield
        except OutputError:
            raise
        except OSError as e:
            raise output_error(field, path, e) from e

    return guard()


def check_folder(path, field: str):
    """Whether the folder ``path`` (named by ``field``) can be used or created by vtb, without
    creating it: an existing, writable folder, or one whose parent is an existing, writable
    folder — vtb creates only the last folder of a path it writes to, never a tree of them
    under a mistyped path. Returns ``path`` as a :class:`~pathlib.Path`; raises an
    :class:`OutputError` naming ``field``, the path and the cause otherwise."""
    import errno as _errno
    import os as _os
    from pathlib import Path

    folder = Path(path) if str(path) else Path(".")
    at = folder if folder.exists() else folder.parent
    if not at.exists():
        raise output_error(field, folder, FileNotFoundError(_errno.ENOENT, f"its parent folder {str(at)!r} does not exist (vtb creates only "
                                                                            "the last folder of a path: check the path for a typo, or create the parent)"))
    if not at.is_dir():
        raise output_error(field, folder, NotADirectoryError(_errno.ENOTDIR, f"{str(at)!r} is a file, not a folder"))
    if not _os.access(at, _os.W_OK | _os.X_OK):
        raise output_error(field, folder, PermissionError(_errno.EACCES, f"{str(at)!r} is not writable"))
    return folder


def make_folder(path, field: str):
    """The folder ``path`` (named by ``field``), created if absent when its parent exists
    (:func:`check_folder`: only the last folder of a path is ever created). Every writer of a
    user's path makes its folder with this. Returns it as a :class:`~pathlib.Path`."""
    folder = check_folder(path, field)
    with writing(field, folder):
        folder.mkdir(exist_ok=True)
    return folder


class MissingExtraError(VtbError, ImportError):
    """An optional dependency a method needs is not installed; ``extra`` names the package
    extra that brings it (``pip install 'vtb[io]'``). Raised before any work is done."""

    def __init__(self, message: str, extra: str | None = None):
        VtbError.__init__(self, message)
        self.extra = extra

    def __str__(self) -> str:
        return self.args[0]

    def __reduce__(self):
        return (type(self), (self.args[0], self.extra))
