"""Whole turns taken out of a circle run's angles, and put back in everything the run reports.

On the circle every force and every gap is 2 pi periodic in the angles, but a
body that goes round carries a growing phi, and the integrator's rounding grows
with it: ulp(phi) is 1.2e-10 rad at phi = 7e5, and two disks going round for
1e5 s lost 5e-9 of their energy at k = 1, against 1.4e-13 for the same pair
oscillating (review). So a run that can go round (a body whose energy reaches
the upper half of the circle: system.energy_reach) takes whole turns out of
its angles every WIND_STEPS steps, once the first unit's angle passes
WIND_AT, and adds them back to every angle it reports (the collision table,
the final state, the mode changes, stroboscopic samples, friction transitions
and dense output): a user sees the same unwrapped phi as before.

The shift S (about m 2 pi) is subtracted from every unit's angle at once, and
exactly: each angle lies within a factor 2 of S (Sterbenz' lemma; checked,
else no shift is taken then), so every gap phi_j - phi_i keeps its last bit
and no contact, cluster or touching pair sees a change. S is the run type's
number nearest m 2 pi plus what earlier shifts left over (error feedback): the
angles stay within half an ulp of S of the true ones however many turns are
taken (a fixed S = fl(2 pi) would have drifted by 2.4e-16 rad a turn).
"""

from __future__ import annotations

import math

import mpmath
import numpy as np

from ..model._numbers import workprec

#: A run that can go round takes whole turns out after every this many steps (the integrator
#: stops there and goes on with the same steps: its results are those of one long call).
WIND_STEPS = 64
#: ... once the first unit's angle is this far from the bottom (m >= 2 turns are taken then, so that
#: every unit, within 2 pi of the first on the circle, is within a factor 2 of the shift).
WIND_AT = 4 * math.pi


class Turns:
    """The whole turns taken out of one run's angles so far (one per run; see the module docstring).

    ``changes``: (records, stroboscopic samples, friction transitions made before the change, the total
    shift after it, in the run's type); an item made after the n-th change is reported with its total.
    """

    __slots__ = ("number", "changes", "_total", "_residual", "offset")

    def __init__(self, precision):
        self.number = precision.number
        self.changes: list = []
        self._total = mpmath.mpf(0)  # the shifts taken, summed (exactly: 256 bits hold their sum)
        self._residual = mpmath.mpf(0)  # m 2 pi summed, less the shifts taken (error feedback)
        self.offset = 0  # the total in the run's type

    def take(self, state, n_coordinates: int, log, friction=None) -> bool:
        """Take whole turns out of ``state[:n_coordinates]`` (a numpy view, in place) where the first is past
        WIND_AT; True if it did. ``log``, ``friction``: where the run's records, samples and transitions are
        counted."""
        first = float(state[0])
        if -WIND_AT < first < WIND_AT:
            return False
        turns = round(first / (2 * math.pi))
        with workprec():
            target = turns * 2 * mpmath.pi + self._residual
            shift = self.number(target)
            low, high = (shift / 2, shift * 2) if turns > 0 else (shift * 2, shift / 2)
            angles = state[:n_coordinates]
            if not all(low <= x <= high for x in angles.tolist()):
                return False  # (not within a factor 2 of the shift, so not exact: the next chunk's will be)
            angles -= shift
            taken = _mpf(shift)
            self._residual = target - taken
            self._total += taken
            self.offset = self.number(self._total)
        self.changes.append((log.count, len(log.strobe), len(friction.transitions) if friction is not None else 0,
                             self.offset))
        return True

    def offset_of(self, kind: int, index: int):
        """The total shift that the ``index``-th item of ``kind`` (0 records, 1 samples, 2 transitions, 0-based)
        was made with."""
        offset = 0
        for change in self.changes:
            if change[kind] > index:
                break
            offset = change[3]
        return offset

    def angles(self, state, n_bodies: int, offset=None) -> list:
        """A full state [phi..., dphi..., extra] as a list, the turns (``offset``, default: all so far) put back."""
        offset = self.offset if offset is None else offset
        out = list(state)
        if offset:
            out[:n_bodies] = [x + offset for x in out[:n_bodies]]
        return out

    def records(self, arrays: tuple, first: int, n_bodies: int) -> tuple:
        """records_to_arrays' columns of the records numbered ``first``, ``first`` + 1, ... (0-based) with the
        turns put back in their angles (the states before and after)."""
        before, after = arrays[2], arrays[3]
        rows = len(before)
        if not self.changes or not rows:
            return arrays
        edges = [0] + [max(0, min(rows, change[0] - first)) for change in self.changes] + [rows]
        offsets = [0] + [change[3] for change in self.changes]
        for start, stop, offset in zip(edges, edges[1:], offsets):
            if stop > start and offset:
                before[start:stop, :n_bodies] += offset
                after[start:stop, :n_bodies] += offset
        return arrays


def _mpf(x):
    """A float, long double, real128 or MPFR real as an mpmath number (inside workprec: exact for the first
    two; the decimal text of the others, ~1e-37 relative, far below the residual's worth)."""
    if isinstance(x, (float, np.floating)):
        numerator, denominator = x.as_integer_ratio()
        return mpmath.mpf(numerator) / denominator
    return mpmath.mpf(str(x))
