"""The scipy baseline of the work-precision study: solve_ivp with terminal events.

The same problem heyroll integrates, written the way one would with scipy:

* the right-hand side of paper eq. (25), phi_k'' = -a_k sin(phi_k) with
  a_k = g / (kappa_k (R - r_k)), vectorised over the bodies with numpy, or
  for two bodies written out with math.sin (faster at N = 2);
* one event per reachable contact, the gap phi_j - phi_i + (offset - beta),
  ``terminal=True`` and ``direction=-1`` (approach only), as heyroll watches;
* at each terminal event the SAME collision law heyroll applies, the impulse
  map of :func:`heyroll.model.laws.impulse_map` with its constants rounded to
  double: D = phi_i' - q phi_j', phi_i' -= a_i D, phi_j' += a_j D;
* then a restart of ``solve_ivp`` from the event time and state
  (``sol.t_events`` / ``sol.y_events``).

Dense output is off (scipy still builds each step's interpolant to locate the
events, and that interpolant is what limits the event times). The implicit
methods (Radau, BDF, LSODA) get the analytic Jacobian. scipy is an optional
dependency (``pip install '.[validation]'``): this module imports it at
import time, so import the module only where scipy is known to be present.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

from heyroll.model.laws import impulse_map

#: Methods that take a Jacobian (``jac=``); the explicit ones would warn on it.
IMPLICIT = frozenset({"Radau", "BDF", "LSODA"})

#: scipy raises any rtol below this to it (with a warning): scipy.integrate._ivp.common.validate_tol.
SMALLEST_RTOL = 100 * np.finfo(float).eps


@dataclass(frozen=True)
class BaselinePair:
    """A watched contact: bodies i (clockwise) and j (0-based), gap constant, law map in double."""

    i: int
    j: int
    gap_constant: float
    q: float
    a_i: float
    a_j: float


@dataclass(frozen=True)
class BaselineProblem:
    """A scene reduced to the doubles solve_ivp needs."""

    a: np.ndarray  # a_k = g / (kappa_k (R - r_k)), shape (N,)
    pairs: tuple[BaselinePair, ...]
    y0: np.ndarray  # [phi_1..phi_N, dphi_1..dphi_N]

    @property
    def n_bodies(self) -> int:
        return int(self.a.size)


@dataclass
class BaselineRun:
    """The collisions one solve_ivp setting found: times, pairs (1-based), status."""

    times: list = field(default_factory=list)
    pairs: list = field(default_factory=list)  # (i, j), bodies numbered from 1
    status: str = "max_collisions"  # max_collisions | t_end | failed
    message: str = ""
    nfev: int = 0
    restarts: int = 0


def problem_from_scene(scene) -> BaselineProblem:
    """Constants of ``scene`` rounded once to double, as heyroll's double runs round them."""
    track, g = scene.track, scene.g
    a = np.array([float(track.angular_stiffness(b, g)) for b in scene.bodies])
    pairs = []
    for p in scene.pairs:
        if not p.reachable:  # heyroll compiles no event for these either
            continue
        m = impulse_map(scene.law, scene.bodies[p.i], scene.bodies[p.j], scene.sigma(p.i), scene.sigma(p.j))
        pairs.append(BaselinePair(p.i, p.j, float(p.gap_constant()), float(m.q), float(m.a_i), float(m.a_j)))
    y0 = np.array([float(x) for x in scene.phi] + [float(x) for x in scene.dphi])
    return BaselineProblem(a=a, pairs=tuple(pairs), y0=y0)


def make_rhs(problem: BaselineProblem, kind: str = "auto"):
    """fun(t, y) and jac(t, y) of phi'' = -a sin(phi).

    ``kind="numpy"``: vectorised over the bodies with numpy. ``kind="two"``
    (two bodies only): written out with ``math.sin``, about half the cost
    per call of the numpy version for N = 2 (numpy's per-call overhead
    dominates four components). ``"auto"`` takes the faster one.
    """
    n = problem.n_bodies
    minus_a = -problem.a
    if kind == "auto":
        kind = "two" if n == 2 else "numpy"

    if kind == "two":
        if n != 2:
            raise ValueError("kind='two' needs two bodies")
        m1, m2 = (float(x) for x in minus_a)
        sin, array = math.sin, np.array

        def rhs(t, y):
            p1, p2, v1, v2 = y.tolist()
            return array([v1, v2, m1 * sin(p1), m2 * sin(p2)])

    elif kind == "numpy":

        def rhs(t, y):
            out = np.empty(2 * n)
            out[:n] = y[n:]
            np.sin(y[:n], out=out[n:])
            out[n:] *= minus_a
            return out

    else:
        raise ValueError(f"unknown kind {kind!r}")

    def jac(t, y):
        J = np.zeros((2 * n, 2 * n))
        J[np.arange(n), n + np.arange(n)] = 1.0
        J[n + np.arange(n), np.arange(n)] = minus_a * np.cos(y[:n])
        return J

    return rhs, jac


def make_events(problem: BaselineProblem) -> list:
    """One terminal event per watched contact: the gap, firing when it closes."""
    events = []
    for pair in problem.pairs:

        def gap(t, y, i=pair.i, j=pair.j, c=pair.gap_constant):
            return y[j] - y[i] + c

        gap.terminal = True
        gap.direction = -1
        events.append(gap)
    return events


def apply_law(pair: BaselinePair, y: np.ndarray, n_bodies: int) -> None:
    """The collision law on the state ``y`` in place (heyroll's impulse map, in double)."""
    vi, vj = n_bodies + pair.i, n_bodies + pair.j
    d = y[vi] - pair.q * y[vj]
    y[vi] -= pair.a_i * d
    y[vj] += pair.a_j * d


def run_baseline(
    problem: BaselineProblem, method: str, rtol: float, n_collisions: int, t_end: float, *,
    atol_scale: float = 1e-2, rhs_kind: str = "auto",
) -> BaselineRun:
    """Integrate with ``solve_ivp(method)`` until ``n_collisions`` collisions or ``t_end``.

    ``atol = rtol * atol_scale`` for every component. After each terminal
    event the law is applied to the event state and solve_ivp restarts there.
    ``rhs_kind``: see :func:`make_rhs`.
    """
    rhs, jac = make_rhs(problem, rhs_kind)
    events = make_events(problem)
    options = {"jac": jac} if method in IMPLICIT else {}
    run = BaselineRun()
    n = problem.n_bodies
    t, y = 0.0, problem.y0.copy()
    while len(run.times) < n_collisions:
        sol = solve_ivp(
            rhs, (t, t_end), y, method=method, rtol=rtol, atol=rtol * atol_scale,
            events=events, dense_output=False, **options,
        )
        run.nfev += int(sol.nfev)
        run.restarts += 1
        if sol.status < 0:
            run.status, run.message = "failed", f"{method} failed at t = {sol.t[-1]:.17g}: {sol.message}"
            return run
        if sol.status == 0:
            run.status, run.message = "t_end", f"no collision before t_end = {t_end:g}"
            return run
        # A terminal event: all events are terminal, so exactly one was recorded.
        fired = [k for k, te in enumerate(sol.t_events) if te.size]
        k = fired[0]
        t = float(sol.t_events[k][-1])
        y = np.array(sol.y_events[k][-1], dtype=float)
        pair = problem.pairs[k]
        apply_law(pair, y, n)
        run.times.append(t)
        run.pairs.append((pair.i + 1, pair.j + 1))
    run.message = f"stopped after {n_collisions} collisions"
    return run
