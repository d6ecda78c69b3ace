"""A small least-recently-used cache for compiled heyoka objects (integrators, compiled functions).

Compilation costs tens to thousands of milliseconds; runs of scenes of one
shape reuse what was compiled for the first (constants are runtime parameters).
"""

from __future__ import annotations

from collections import OrderedDict


class CompiledCache:
    """``get(key, build)``: the entry under ``key``, built by ``build()`` the first time."""

    def __init__(self, size: int):
        self.size = size
        self._entries: OrderedDict = OrderedDict()

    def __contains__(self, key) -> bool:
        return key in self._entries

    def get(self, key, build):
        entry = self._entries.get(key)
        if entry is None:
            entry = build()
            self._entries[key] = entry
            if len(self._entries) > self.size:
                self._entries.popitem(last=False)
        else:
            self._entries.move_to_end(key)
        return entry
