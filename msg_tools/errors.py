"""Exceptions raised by the MCAP tools. Each carries a one-line message a CLI prints as it is (exit code 2).

They derive from fastep_core.errors.FastepError, so a command that already turns FastepError into one line on
stderr handles recordings the same way.
"""

from __future__ import annotations

from fastep_core.errors import FastepError

__all__ = ['NotMcapError', 'RecordingError', 'TruncatedRecordingError']


class RecordingError(FastepError):
    """A recording cannot be read or written: missing, unreadable, corrupt, or of an unknown message type."""


class NotMcapError(RecordingError):
    """The file is not an MCAP file at all (empty, or its first bytes are not the MCAP magic)."""


class TruncatedRecordingError(RecordingError):
    """The file was cut off (no summary/footer) and not one complete message could be recovered from it."""
