"""The one family of errors deformap raises at its public boundary.

Every error names the argument (or file, field, topic), what was expected and what came; each
class also derives from the closest builtin (``ValueError``, ...) for generic handlers.
"""

from __future__ import annotations

__all__ = ["ConfigError", "DeformapError", "EnvironmentStateError", "FileFormatError",
           "FileWriteError", "InvalidArgumentError", "MissingDependencyError",
           "NotPositiveDefiniteError"]


class DeformapError(Exception):
    """Base class of every error deformap raises on purpose."""


class InvalidArgumentError(DeformapError, ValueError):
    """An argument has the wrong shape, dtype, range or value."""


class NotPositiveDefiniteError(DeformapError, ArithmeticError):
    """A covariance or stiffness matrix could not be factorised even with added jitter."""


class FileFormatError(DeformapError, ValueError):
    """A file is missing, truncated, corrupted, or lacks a required field."""


class FileWriteError(DeformapError, OSError):
    """A file could not be written (no space left, a read-only file system, a quota, no
    permission); the message names the file and the cause, ``errno`` is the system's."""


class ConfigError(DeformapError, ValueError):
    """A configuration or scenario file has an unknown key or a bad value."""


class EnvironmentStateError(DeformapError, RuntimeError):
    """An ``Environment`` was asked to do something its current state does not allow."""


class MissingDependencyError(DeformapError, ImportError):
    """An optional dependency is not installed; the message names the extra to install."""


def missing_extra(module: str, extra: str, purpose: str) -> MissingDependencyError:
    """The error for the optional ``module`` (``"rosbags"``) of the deformap ``extra``
    (``"ros"``) missing while ``purpose`` (``"reading ROS 2 bags"``)."""
    return MissingDependencyError(
        f"{purpose} needs the optional package {module!r}, which is not installed; "
        f"install it with: pip install 'deformap[{extra}]'")
