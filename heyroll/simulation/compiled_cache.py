"""A small least-recently-used cache for compiled heyoka objects (integrators, compiled functions).

Compilation costs tens to thousands of milliseconds; runs of scenes of one
shape reuse what was compiled for the first (constants are runtime parameters).
"""

from __future__ import annotations

import functools
from collections import OrderedDict, deque


class HashedKey:
    """A tuple as a cache key, hashed once (a key looked up at every run of a shape)."""

    __slots__ = ("values", "_hash")

    def __init__(self, values: tuple):
        self.values = values
        self._hash = hash(values)

    def __hash__(self) -> int:
        return self._hash

    def __eq__(self, other) -> bool:
        return self is other or (isinstance(other, HashedKey) and self._hash == other._hash
                                 and self.values == other.values)

    def __repr__(self) -> str:
        return f"HashedKey({self.values!r})"


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


def _memoized(f, memo_of, keep: int | None = None):
    """``f(scene, *args)`` kept in ``memo_of(scene)`` (a dict) by (f, args); with ``keep`` only the last ``keep``
    scenes' values are kept (the older ones are dropped from their memos)."""
    recent: deque = deque()

    @functools.wraps(f)
    def cached(scene, *args):
        memo = memo_of(scene)
        key = (f, args)
        value = memo.get(key, memo)
        if value is memo:
            value = memo[key] = f(scene, *args)
            if keep is not None:
                recent.append((memo, key))
                while len(recent) > keep:
                    old, old_key = recent.popleft()
                    old.pop(old_key, None)
        return value

    return cached


def by_constants():
    """Cache ``f(scene, *args)`` by the scene's constants (model.scene.Scene.constants) and ``args``:
    for what depends on a scene's bodies, track and laws but not on its state, so that scenes which
    differ only in where they start (a sweep's points) compute it once. Kept in the constants' own
    ``memo`` (interned, bounded in number): a lookup is one dict access, ~0.3 us, where a shared
    least-recently-used table took ~1 us (measured; a run's set-up asks several)."""
    return lambda f: _memoized(f, lambda scene: scene.constants.memo)


def by_scene(f=None, *, keep: int | None = None):
    """Cache ``f(scene, *args)`` with the scene object itself (its ``memo``), by ``args``: for what
    depends on a scene's state too (a run's start, what its energy can reach). Kept with the scene,
    not in a table keyed by it, so that a sweep's new point pays no hashing of its exact numbers
    (~5 us a point, measured). ``keep``: only the last ``keep`` scenes keep their value (it holds a
    compiled system: results that keep their scenes must not keep every one of those, review)."""

    def decorate(f):
        return _memoized(f, lambda scene: scene.memo, keep)

    return decorate if f is None else decorate(f)
