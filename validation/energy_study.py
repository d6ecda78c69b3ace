"""Reusable pieces of the long-run energy study (validation/long_runs.py).

* :class:`EnergySink` - a collision sink (see ``heyroll.simulate(sink=...)``)
  that keeps the relative energy error E/E0 - 1 after each collision,
  downsampled: on a log-spaced grid of collision indices, at the end of fixed
  blocks of collisions, and each block's maximum |E/E0 - 1|; never the whole
  table. It also splits the error into the part made by the collision map
  (sum of E_after - E_before over collisions) and the part made by the
  integration between collisions (the rest), and watches for an exactly
  periodic floating-point trajectory.
* :func:`fit_growth_exponent` - log-log least squares of an error vs N.
* :func:`find_recurrence` - the first exact (bitwise) recurrence of a row in a
  table of states: a deterministic map that revisits a state is periodic from
  then on.
* :func:`rounding_variance` - a model of the energy error of rounding a
  state to double once (what every integration step does).
* :func:`structure_exponent` - the growth exponent of one trajectory from the
  mean squared increments of its error over lags (random walk: 0.5).

Energies are evaluated in numpy's extended type (x86: 64-bit mantissa) from
the float64 states and constants rounded once from the scene's exact values,
so the evaluation adds ~1e-19 to each value: what is measured is the error of
the double-precision trajectory, not of the energy formula.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np

from heyroll.simulation.result import body_constants, body_energies

#: numpy's extended float where it has more bits than a double, else float64.
EXTENDED = np.longdouble if np.finfo(np.longdouble).nmant > 52 else np.float64


def _extended_number(x):
    with mpmath.workprec(256):
        return EXTENDED(mpmath.nstr(mpmath.mpf(x), 25, strip_zeros=False))


def energy_constants(scene):
    """Body constants of ``scene`` in the extended type."""
    return body_constants(scene, _extended_number)


def total_energy(constants, states) -> np.ndarray:
    """Total mechanical energy of each state row, in the extended type."""
    states = np.atleast_2d(np.asarray(states)).astype(EXTENDED)
    return body_energies(constants, states).sum(axis=1)


def rounding_variance(constants, states) -> np.ndarray:
    """Variance of E from rounding each component of each float64 state row to nearest (ulp^2 / 12 each).

    dE/dphi = W sin phi, dE/dphi' = M phi' (eq. 26); a model of what storing
    the state in double costs the energy at every integration step.
    """
    states = np.atleast_2d(np.asarray(states, dtype=float))
    n = constants.generalized_mass.size
    phi, dphi = states[:, :n], states[:, n:]
    w = np.asarray(constants.weight_moment, dtype=float)
    m = np.asarray(constants.generalized_mass, dtype=float)
    d_phi = w * np.sin(phi) * np.spacing(np.abs(phi))
    d_dphi = m * dphi * np.spacing(np.abs(dphi))
    return np.sum(d_phi**2 + d_dphi**2, axis=1) / 12


def initial_state(scene, precision=None) -> np.ndarray:
    """The scene's initial state as the run rounds it (float64 for double)."""
    number = float if precision is None else precision.number
    return np.array([number(x) for x in scene.phi] + [number(x) for x in scene.dphi], dtype=float)


def log_grid(n_max: int, per_decade: int = 20) -> np.ndarray:
    """Collision indices 1..n_max, ``per_decade`` log-spaced per decade, n_max included.

    The grid does not depend on n_max below it, so runs of different lengths
    share their grid points.
    """
    if n_max < 1:
        return np.zeros(0, dtype=np.int64)
    k = np.arange(0, int(math.ceil(per_decade * math.log10(n_max))) + 1)
    grid = np.unique(np.floor(10.0 ** (k / per_decade) + 1e-9).astype(np.int64))
    grid = grid[grid <= n_max]
    return np.unique(np.append(grid, n_max))


def find_recurrence(rows) -> tuple[int, int] | None:
    """The first row equal (bit for bit) to an earlier one, as (index, period), else None.

    ``rows`` is a 2-D array (one state per row). ``period`` is the distance to
    the latest earlier occurrence of that row.
    """
    rows = np.ascontiguousarray(rows)
    if rows.ndim != 2 or rows.shape[0] < 2:
        return None
    view = rows.view(np.dtype((np.void, rows.dtype.itemsize * rows.shape[1]))).ravel()
    order = np.argsort(view, kind="stable")  # equal rows stay in index order
    ordered = view[order]
    same = ordered[1:] == ordered[:-1]
    if not same.any():
        return None
    earlier, later = order[:-1][same], order[1:][same]
    k = int(np.argmin(later))
    return int(later[k]), int(later[k] - earlier[k])


def fit_growth_exponent(n, err, n_min=None, n_max=None) -> tuple[float, float]:
    """Least-squares fit of log10|err| = p log10 n + c over n_min <= n <= n_max: (p, 10**c)."""
    n = np.asarray(n, dtype=float)
    err = np.abs(np.asarray(err, dtype=float))
    mask = np.isfinite(err) & (err > 0) & (n > 0)
    if n_min is not None:
        mask &= n >= n_min
    if n_max is not None:
        mask &= n <= n_max
    if mask.sum() < 2:
        return float("nan"), float("nan")
    p, c = np.polyfit(np.log10(n[mask]), np.log10(err[mask]), 1)
    return float(p), float(10.0**c)


def structure_function(series, max_lag_fraction: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """Mean squared increment S(L) = <(x[n+L] - x[n])^2> at log-spaced lags L (in samples)."""
    x = np.asarray(series, dtype=float)
    top = max(1, int(len(x) * max_lag_fraction))
    lags = np.unique(np.round(np.logspace(0, math.log10(top), 12)).astype(int))
    s = np.array([np.mean((x[lag:] - x[:-lag]) ** 2) for lag in lags])
    return lags, s


def structure_exponent(series, step: int = 1, max_lag_fraction: float = 0.1) -> float:
    """Growth exponent of one trajectory: slope of log sqrt(S(L)) vs log L (random walk 0.5, drift 1)."""
    lags, s = structure_function(series, max_lag_fraction)
    p, _ = fit_growth_exponent(lags * step, np.sqrt(s))
    return p


class EnergySink:
    """A collision sink that records the relative energy error, downsampled.

    After the run:

    * ``grid_n``, ``grid_err``: E/E0 - 1 just after collision n, n on
      :func:`log_grid` (``per_decade`` points per decade) up to ``n_max``
      and at the collision numbers ``extra``;
      ``grid_map``, ``grid_flight``: the parts of it made by the collision map
      and by the integration between collisions (they add up to grid_err);
    * ``block_end_err``: E/E0 - 1 after collisions block, 2 block, ...;
      ``block_max``: max |E/E0 - 1| within each block;
    * ``last_n``, ``last_err``, ``max_abs_err``;
    * ``recurrence``: (collision number, period) of the first state after a
      collision equal bit for bit to an earlier one (periods up to
      ``window`` collisions are seen), else None; ``distinct_last``: the
      number of distinct energy-error values in the latest chunk of at least
      1000 collisions (``frozen``: under 1 % of them).
    """

    def __init__(self, n_max: int, *, per_decade: int = 20, blocks: int = 1000, window: int = 65536, extra=()):
        self.n_max = int(n_max)
        self.grid = np.union1d(log_grid(self.n_max, per_decade), np.asarray(extra, dtype=np.int64))
        self.block = max(1, self.n_max // blocks)
        self.window = window

    # -- sink protocol -------------------------------------------------
    def open(self, scene, pairs, precision) -> None:
        if precision.name != "double":
            raise ValueError("EnergySink reads float64 states: double runs only")
        self.constants = energy_constants(scene)
        self.e0 = total_energy(self.constants, initial_state(scene, precision))[0]
        self.last_e_after = self.e0
        self.map_sum = EXTENDED(0)
        self.flight_sum = EXTENDED(0)
        self.grid_n, self.grid_err, self.grid_map, self.grid_flight = [], [], [], []
        self.block_end_err, self.block_max = [], []
        self._block_running_max = 0.0
        self.last_n, self.last_err, self.max_abs_err = 0, 0.0, 0.0
        self.recurrence = None
        self.distinct_last, self._judged_rows = None, 0
        self._rounding_var, self._rounding_rows = 0.0, 0
        self._tail = None  # the last ``window`` states (recurrence across chunks)
        self._tail_first = 1

    def write(self, chunk: tuple, first_number: int) -> None:
        before, after = chunk[2], chunk[3]  # (times, pair_numbers, before, after[, flags])
        m = len(after)
        if m == 0:
            return
        e_before = total_energy(self.constants, before)
        e_after = total_energy(self.constants, after)
        jumps = e_after - e_before
        flights = e_before - np.concatenate(([self.last_e_after], e_after[:-1]))
        map_cum = self.map_sum + np.cumsum(jumps)
        flight_cum = self.flight_sum + np.cumsum(flights)
        self.map_sum, self.flight_sum = map_cum[-1], flight_cum[-1]
        self.last_e_after = e_after[-1]
        err = (e_after / self.e0 - 1).astype(float)
        numbers = np.arange(first_number, first_number + m)

        sel = (self.grid >= first_number) & (self.grid < first_number + m)
        idx = self.grid[sel] - first_number
        self.grid_n.extend(self.grid[sel].tolist())
        self.grid_err.extend(err[idx].tolist())
        self.grid_map.extend((map_cum[idx] / self.e0).astype(float).tolist())
        self.grid_flight.extend((flight_cum[idx] / self.e0).astype(float).tolist())

        # blocks of ``block`` collisions: end value and max |err|
        absolute = np.abs(err)
        block_id = (numbers - 1) // self.block
        starts = np.flatnonzero(np.r_[True, block_id[1:] != block_id[:-1]])
        ends = np.r_[starts[1:], m]
        maxima = np.maximum.reduceat(absolute, starts)
        for end, mx in zip(ends.tolist(), maxima.tolist()):
            self._block_running_max = max(self._block_running_max, mx)
            if numbers[end - 1] % self.block == 0:  # the block is complete
                self.block_max.append(self._block_running_max)
                self.block_end_err.append(float(err[end - 1]))
                self._block_running_max = 0.0

        for states in (before, after):
            self._rounding_var += float(np.sum(rounding_variance(self.constants, states))) / float(self.e0) ** 2
            self._rounding_rows += len(states)

        self.max_abs_err = max(self.max_abs_err, float(absolute.max()))
        self.last_n, self.last_err = int(numbers[-1]), float(err[-1])
        if m >= 1000 or self._judged_rows < 1000:  # judge on the latest chunk of >= 1000 collisions
            self.distinct_last, self._judged_rows = int(np.unique(err).size), m

        if self.recurrence is None:
            states = np.asarray(after, dtype=float)
            rows = states if self._tail is None else np.concatenate((self._tail, states))
            first = first_number if self._tail is None else self._tail_first
            found = find_recurrence(rows)
            if found is not None:
                self.recurrence = (first + found[0], found[1])
            keep = rows[-self.window :]
            self._tail = np.array(keep, copy=True)
            self._tail_first = first + len(rows) - len(keep)

    def close(self) -> None:
        self._tail = None

    # -- results ---------------------------------------------------------
    @property
    def periodic(self) -> bool:
        return self.recurrence is not None

    @property
    def rounding_sigma(self) -> float:
        """Model: RMS relative energy change of rounding every state component once (over collision states)."""
        return math.sqrt(self._rounding_var / self._rounding_rows) if self._rounding_rows else float("nan")

    @property
    def frozen(self) -> bool:
        """The energy error took fewer than 1 % distinct values over the latest chunk of >= 1000 collisions."""
        return self._judged_rows >= 1000 and self.distinct_last * 100 < self._judged_rows

    def as_dict(self) -> dict:
        return {
            "n_max": self.n_max,
            "e0": float(self.e0),
            "grid_n": list(self.grid_n),
            "grid_err": list(self.grid_err),
            "grid_map": list(self.grid_map),
            "grid_flight": list(self.grid_flight),
            "block": self.block,
            "block_end_err": list(self.block_end_err),
            "block_max": list(self.block_max),
            "last_n": self.last_n,
            "last_err": self.last_err,
            "max_abs_err": self.max_abs_err,
            "map_total": float(self.map_sum / self.e0),
            "flight_total": float(self.flight_sum / self.e0),
            "rounding_sigma": self.rounding_sigma,
            "recurrence": self.recurrence,
            "distinct_last": self.distinct_last,
            "periodic": self.periodic,
            "frozen": self.frozen,
        }
