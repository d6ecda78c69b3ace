"""Errors raised for bad input.

Every error about a scene names the field and the rule it breaks, in one line,
so the CLI can print it as it is (exit code 2) and an API user can catch it as
a ``ValueError``.
"""

from __future__ import annotations

import re

#: A number as Python shows it (the scene file's decimals, mpmath's numbers): shown as the user wrote it.
_NUMBER_REPR = re.compile(r"(?:Decimal|mpf)\('([^']*)'\)")


class SceneError(ValueError):
    """A scene (bodies, track, law, run settings) breaks a rule.

    ``field`` is the dotted path of the offending entry, e.g. ``bodies[2].radius``.
    """

    def __init__(self, field: str, rule: str):
        self.field = field
        # "got Decimal('-0.2')" reads "got -0.2": rules format their values with !r (strings get quotes)
        self.rule = rule = _NUMBER_REPR.sub(r"\1", rule)
        super().__init__(f"{field}: {rule}")


class SceneFileError(SceneError):
    """A scene file cannot be read or parsed (not TOML, missing file)."""
