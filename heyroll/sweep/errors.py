"""Errors of a sweep's input: each names the KEY, flag or path and the rule, in one line.

They are SceneErrors (ValueErrors with ``field`` and ``rule``), so the CLI
prints them as it prints every other bad input (exit code 2) and an API user
catches them as ValueErrors.
"""

from __future__ import annotations

from ..errors import SceneError


class SweepError(SceneError):
    """A sweep's specification breaks a rule (a range, a count, --keep, a [sweep] table entry)."""


class SweepKeyError(SweepError):
    """A KEY names no numeric field of the scene (``field`` is the KEY as given)."""


class SweepStoreError(SweepError):
    """The output store cannot be used: it belongs to a different sweep, or it is not a sweep store."""


class SchedulerError(SweepError):
    """The dask.distributed scheduler given with --scheduler cannot be reached."""
