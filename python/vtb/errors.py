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
