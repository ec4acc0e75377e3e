"""Exceptions raised by skyscatter.

Every error a user can trigger with bad input derives from :class:`SkyscatterError`, which itself derives
from :class:`ValueError`, so callers may catch either. The command-line interface prints the message of any
:class:`SkyscatterError` on one line and exits with status 2.
"""

from __future__ import annotations


class SkyscatterError(ValueError):
    """Base class of every error skyscatter raises for invalid input or files."""


class InvalidParameterError(SkyscatterError):
    """A parameter is outside the range the model supports (the message states the allowed range)."""


class InvalidDirectionError(SkyscatterError):
    """A direction array has the wrong shape, contains NaN/inf or has zero length."""


class SunBelowHorizonError(InvalidParameterError):
    """The sun is below the horizon and the model cannot represent that case."""


class FileFormatError(SkyscatterError):
    """A file could not be parsed; the message names the file and, where possible, the line."""


class OutputError(SkyscatterError):
    """An output file could not be written (for example the folder does not exist or is read-only)."""


class MissingDependencyError(SkyscatterError):
    """An optional package a feature needs is not installed (the message names it and the extra that installs it)."""
