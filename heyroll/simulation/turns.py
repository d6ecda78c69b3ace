"""Whole turns taken out of a circle run's angles, and put back in everything the run reports.

On the circle every force and every gap is 2 pi periodic in the angles, but a
body that goes round carries a growing phi, and the integrator's rounding grows
with it: ulp(phi) is 1.2e-10 rad at phi = 7e5, and two disks going round for
1e5 s lost 5e-9 of their energy at k = 1, against 1.4e-13 for the same pair
oscillating (review). So a run that can go round (a body whose energy reaches
the upper half of the circle: system.energy_reach) takes whole turns out of
its angles between stretches of integration (64 steps and more: Winder),
once the first unit's angle passes WIND_AT, and adds them back to every angle it reports (the collision table,
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

#: A run that can go round takes whole turns out after every this many steps at least (the integrator
#: stops there and goes on with the same steps: its results are those of one long call); Winder
#: sets the stretches' lengths from there.
WIND_STEPS = 64
#: ... so that its first angle moves about this far between two looks (rad), or, with dense output,
#: WIND_DENSE (a continuous output per stretch costs ~1 ms and ~0.2 MB: review).
WIND_GROWTH = 8 * math.pi
WIND_DENSE = 1024.0
#: ... once the first unit's angle is this far from the bottom (m >= 2 turns are taken then, so that
#: every unit, within 2 pi of the first on the circle, is within a factor 2 of the shift).
WIND_AT = 4 * math.pi


class Turns:
    """The whole turns taken out of one run's angles so far (one per run; see the module docstring).

    ``changes``: (records, stroboscopic samples, friction transitions made before the change, the total
    shift after it, in the run's type); an item made after the n-th change is reported with its total.
    """

    __slots__ = ("number", "double", "changes", "_total", "_residual", "offset", "_pending")

    def __init__(self, precision):
        self.number = precision.number
        self.double = precision.name == "double"
        self.changes: list = []
        # the shifts taken, summed, and m 2 pi summed less them (error feedback): in double as (hi, lo) pairs of
        # floats (a turn taken in ~3 us: with mpmath it took 25 us, a body circling alone twice as long), else
        # as mpmath numbers (256 bits hold them exactly)
        self._total = (0.0, 0.0) if self.double else mpmath.mpf(0)
        self._residual = 0.0 if self.double else mpmath.mpf(0)
        self.offset = 0  # the total in the run's type
        self._pending = None  # a shift begun: (the first angle before it, what it makes of the totals)

    def take(self, state, n_coordinates: int, log, friction=None) -> bool:
        """Take whole turns out of ``state[:n_coordinates]`` (a numpy view, in place) where the first is past
        WIND_AT; True if it did. ``log``, ``friction``: where the run's records, samples and transitions are
        counted."""
        first = float(state[0])
        if -WIND_AT < first < WIND_AT:
            return False
        turns = round(first / (2 * math.pi))
        shift, residual, total, offset = self._double_shift(turns) if self.double else self._shift(turns)
        low, high = (shift / 2, shift * 2) if turns > 0 else (shift * 2, shift / 2)
        angles = state[:n_coordinates]
        if not all(low <= x <= high for x in angles.tolist()):
            return False  # (not within a factor 2 of the shift, so not exact: the next chunk's will be)
        change = (log.count, len(log.strobe), len(friction.transitions) if friction is not None else 0, offset)
        # The state moves in one numpy operation, then the totals follow: a Ctrl-C between the two (it left the
        # final state whole turns off, review: 17 of 60 interrupted runs) is settled by settle()
        self._pending = (angles[0], residual, total, offset, change)
        angles -= shift
        self._commit()
        return True

    def _commit(self) -> None:
        _, self._residual, self._total, self.offset, change = self._pending
        self.changes.append(change)
        self._pending = None

    def settle(self, state) -> None:
        """After an interruption: a shift that moved ``state`` is recorded, one that did not is forgotten."""
        if self._pending is not None:
            if state[0] != self._pending[0]:
                self._commit()
            else:
                self._pending = None

    def _shift(self, turns: int) -> tuple:
        """(shift, residual, total, offset) in mpmath (long, quad, mp)."""
        target = self._target(turns)
        with workprec():
            shift = self.number(target)
            taken = _mpf(shift)
            total = self._total + taken
            return shift, target - taken, total, self.number(total)

    def _target(self, turns: int):
        """m 2 pi plus what the shifts so far left over, at model precision."""
        with workprec():
            return turns * 2 * mpmath.pi + self._residual

    def _double_shift(self, turns: int) -> tuple:
        """(shift, residual, total, offset) in floats: m 2 pi + residual rounded once, with 2 pi as three floats
        whose first has 13 trailing zero bits (m hi exact for |m| < 2^13), and the total as a compensated sum."""
        hi, mid, lo = _TWO_PI
        m = float(turns)
        if abs(m) >= 2**13:  # (a start far out: once, in mpmath)
            target = self._target(turns)
            shift = float(target)
            with workprec():
                residual = float(target - mpmath.mpf(shift))
        else:
            small = m * mid + (m * lo + self._residual)
            shift = m * hi + small
            residual = (m * hi - shift) + small  # (m hi - shift: exact, Sterbenz)
        total_hi, total_lo = self._total
        s = total_hi + shift  # Knuth's two-sum: the total to ~106 bits
        b = s - total_hi
        total_lo += (total_hi - (s - b)) + (shift - b)
        return shift, residual, (s, total_lo), s + total_lo

    def offset_of(self, kind: int, index: int):
        """The total shift that the ``index``-th item of ``kind`` (0 records, 1 samples, 2 transitions, 0-based)
        was made with."""
        offset = 0
        for change in self.changes:
            if change[kind] > index:
                break
            offset = change[3]
        return offset

    def items(self, items, kind: int) -> tuple:
        """Stroboscopic samples (t, full state; ``kind`` 1) or friction transitions (t, body, old, new, q, dq;
        ``kind`` 2) as reported: the whole turns each was made with put back in its angles."""
        out = []
        for n, item in enumerate(items):
            offset = self.offset_of(kind, n) if self.changes else 0
            if offset and kind == 1:
                item = (item[0], self.angles(item[1], len(item[1]) // 2, offset))
            elif offset:
                item = item[:4] + (item[4] + offset,) + item[5:]
            out.append(item)
        return tuple(out)

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


class Winder:
    """Takes whole turns out of a run's angles between stretches of integration, and sets their length: as
    many steps as moved the first angle by about ``growth`` radians the last time (between WIND_STEPS and
    ``most``). A fixed 64 steps made one heyoka continuous output (~1 ms, ~0.2 MB: it holds compiled code)
    per 64 steps of a dense run going round (review: 5.9 s and 1.35 GB against 0.22 s and 0.22 GB), and one
    Python round trip per 64 steps of a body circling alone."""

    __slots__ = ("turns", "n_coordinates", "log", "friction", "growth", "most", "steps", "_last")

    def __init__(self, turns: Turns, n_coordinates: int, log, friction, growth: float, most: int):
        self.turns, self.n_coordinates, self.log, self.friction = turns, n_coordinates, log, friction
        self.growth, self.most, self.steps, self._last = growth, most, WIND_STEPS, None

    def __call__(self, state, steps: int) -> None:
        """After a stretch of ``steps`` steps that left ``state`` (the integrator's, in place)."""
        first = float(state[0])
        if self._last is not None and steps:
            moved = abs(first - self._last)
            self.steps = self.most if moved * self.most <= self.growth * steps else \
                max(WIND_STEPS, int(steps * self.growth / moved))
        self.turns.take(state, self.n_coordinates, self.log, self.friction)
        self._last = float(state[0])


def _two_pi_parts() -> tuple:
    with workprec():
        two_pi = 2 * mpmath.pi
        hi = float(mpmath.ldexp(mpmath.floor(mpmath.ldexp(two_pi, 37)), -37))  # 40 bits: 2 pi < 8
        mid = float(two_pi - hi)
        return hi, mid, float(two_pi - hi - mid)


_TWO_PI = _two_pi_parts()


def _mpf(x):
    """A float, long double, real128 or MPFR real as an mpmath number (inside workprec: exact for the first
    two; the decimal text of the others, ~1e-37 relative, far below the residual's worth)."""
    if isinstance(x, (float, np.floating)):
        numerator, denominator = x.as_integer_ratio()
        return mpmath.mpf(numerator) / denominator
    return mpmath.mpf(str(x))
