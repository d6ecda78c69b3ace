"""Exact collision sequence of bodies rolling inside a circle, in mpmath.

An independent reference for the heyoka engine. It reads only the raw inputs
of a :class:`heyroll.Scene` (g, R, each body's r, m, kappa, the initial
phi, phi', the law's name and restitution) and derives everything else here:

* the pendulum constant a = g / (kappa (R - r)) of every body (paper eq. 25);
* the contact angle beta of each neighbour pair (eq. 44);
* the law's generalized velocity u = c phi' and inertia M (eqs. 10-11, 22-24).

Between collisions each body is its own :class:`ExactPendulum` (Jacobi
elliptic functions). The gap of a neighbour pair (i, j), j counter-clockwise
of i, is

    g(t) = phi_j(t) + offset - phi_i(t) - beta_ij,   offset = 2 pi for (N, 1), else 0,

and the next collision is the earliest root, over all pairs, where the gap
reaches 0 while closing (g' < 0). Roots are never skipped: from a time where
g >= 0, since |g''| = |a_i sin phi_i - a_j sin phi_j| <= G2 = a_i + a_j,

    g(t + h) >= g + g' h - G2 h^2 / 2 > 0    for 0 <= h < h* = (g' + sqrt(g'^2 + 2 G2 g)) / G2,

so stepping by h* can never jump over a root; the steps shrink
quadratically onto a transversal root, which Newton's method then polishes
at full precision.

The law (paper eqs. 10-11) on u = c phi' with inertias M, i clockwise, j
counter-clockwise, restitution k:

    u_i+ = u_i - (1 + k) / (1 + M_i/M_j) (u_i - u_j),
    u_j+ = u_j + (1 + k) / (1 + M_j/M_i) (u_i - u_j),

* ``hedrih``: u = omega_P = (R - r)/r phi' (eq. 23), M = J_P = kappa m r^2 (eq. 24);
* ``newton``: u = v_C = (R - r) phi' (eq. 22), M = m;
* ``newton_generalized``: u = phi', M = kappa m (R - r)^2 (eq. 21).

Nothing from ``heyroll.model.laws`` or ``heyroll.simulation`` is used.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import random

import mpmath
import numpy as np

from .pendulum import GUARD_DPS, ExactPendulum

#: Columns of :func:`reference_table`, a subset of the engine's collision table.
REFERENCE_COLUMNS = (
    "n", "t", "i", "j", "q_i", "q_j",
    "dq_i_before", "dq_j_before", "dq_i_after", "dq_j_after",
)

#: Safety cap on the safe steps spent looking for one root of one gap.
MAX_STEPS_PER_ROOT = 200_000


@dataclass(frozen=True)
class ReferenceCollision:
    """One collision: time, bodies (numbered from 1, i clockwise of j), positions and rates."""

    t: mpmath.mpf
    i: int
    j: int
    q_i: mpmath.mpf
    q_j: mpmath.mpf
    dq_i_before: mpmath.mpf
    dq_j_before: mpmath.mpf
    dq_i_after: mpmath.mpf
    dq_j_after: mpmath.mpf


@dataclass
class ReferenceRun:
    """A reference run: collisions, why it stopped, and the final pendulums."""

    collisions: list = field(default_factory=list)
    status: str = "max_collisions"  # max_collisions | t_end | contact | inconsistent
    message: str = ""
    pendulums: list = field(default_factory=list)
    steps: int = 0


@dataclass(frozen=True)
class _Pair:
    i: int  # 0-based, clockwise body
    j: int  # 0-based, counter-clockwise body
    constant: mpmath.mpf  # offset - beta


def _contact_angle(R, ri, rj):
    """beta from the triangle C0 C_i C_j (paper eq. 44)."""
    rho_i, rho_j = R - ri, R - rj
    return mpmath.acos((rho_i**2 + rho_j**2 - (ri + rj) ** 2) / (2 * rho_i * rho_j))


def _law_variables(law_name, R, body):
    """(c, M) of u = c phi' and the law's inertia M for one body."""
    r, m, kappa = mpmath.mpf(body.radius), mpmath.mpf(body.mass), mpmath.mpf(body.kappa)
    rho = R - r
    if law_name == "hedrih":
        if r == 0:
            raise ValueError("the 'hedrih' law needs rolling bodies (r > 0)")
        return rho / r, kappa * m * r**2
    if law_name == "newton":
        return rho, m
    if law_name == "newton_generalized":
        return mpmath.mpf(1), kappa * m * rho**2
    raise ValueError(f"unknown law {law_name!r}")


def apply_law(c_i, M_i, c_j, M_j, k, dphi_i, dphi_j):
    """Outgoing (phi_i', phi_j') by the Newton-type law on u = c phi' (eqs. 10-11)."""
    u_i, u_j = c_i * dphi_i, c_j * dphi_j
    du = u_i - u_j
    u_i_out = u_i - (1 + k) / (1 + M_i / M_j) * du
    u_j_out = u_j + (1 + k) / (1 + M_j / M_i) * du
    return u_i_out / c_i, u_j_out / c_j


def _first_root(pair, pendulums, a, t_start, t_limit, dps, counter):
    """Earliest t in [t_start, t_limit] where the pair's gap reaches 0 while closing, or None.

    Safe steps h* (module docstring) from t_start: each lands where the gap
    is still >= 0, so no root is ever stepped over. Near a transversal root
    the steps converge onto it quadratically; once the gap is below
    10^-dps rad and closing, Newton's method polishes the time. A grazing
    approach that does not touch is stepped past (the bound lets the steps
    cross the gap's minimum).
    """
    pi_, pj_ = pendulums[pair.i], pendulums[pair.j]
    G2 = a[pair.i] + a[pair.j]
    tol_gap = mpmath.mpf(10) ** (-dps)

    def gap(t):
        phi_i, dphi_i = pi_.state(t)
        phi_j, dphi_j = pj_.state(t)
        return phi_j + pair.constant - phi_i, dphi_j - dphi_i

    t = t_start
    for _ in range(MAX_STEPS_PER_ROOT):
        counter[0] += 1
        g, gp = gap(t)
        if gp < 0 and g <= tol_gap:
            return _polish(gap, t, dps)
        # Rounding can leave g a hair below zero right after a collision
        # (the pair then separates, gp > 0): the bound needs g >= 0.
        g = max(g, mpmath.mpf(0))
        h = (gp + mpmath.sqrt(gp * gp + 2 * G2 * g)) / G2
        t = t + h
        if t > t_limit:
            return None
    raise RuntimeError(
        f"no convergence after {MAX_STEPS_PER_ROOT} safe steps for bodies {pair.i + 1}, {pair.j + 1} "
        f"near t = {mpmath.nstr(t, 17)} (grazing contact?)"
    )


def _polish(gap, t, dps):
    """A few Newton steps on a closing gap already below 10^-dps rad."""
    tol_t = mpmath.mpf(10) ** (-(dps + 3))
    for _ in range(8):
        g, gp = gap(t)
        if gp >= 0:  # tangential contact: the safe steps' point is the best there is
            return t
        step = g / gp
        t = t - step
        if abs(step) <= tol_t * (1 + abs(t)):
            break
    return t


def run_reference(
    scene, n_collisions: int, dps: int = 40, t_end=None, *, double_inputs: bool = False, jitter=0, seed: int = 0
) -> ReferenceRun:
    """The first ``n_collisions`` collisions of ``scene`` (stopping at ``t_end``).

    ``t_end`` defaults to the scene's run setting. With ``double_inputs`` the
    numbers a double-precision integrator has to round (every a_k, every gap
    constant offset - beta, the initial phi and phi') are rounded once to
    IEEE double before the exact solution starts: the reference then solves
    exactly the problem a double run integrates, which separates the
    integration and event-location error from the unavoidable input rounding.
    (Rates after collisions are never rounded.)

    ``jitter`` (default 0: exact) is a validation tool, not physics: after
    every collision the two positions and the two outgoing rates are each
    multiplied by (1 + jitter * N(0, 1)) (``random.Random(seed)``). With
    jitter = 2**-53 (the unit roundoff of double) and ``double_inputs`` this
    models an ideal double-precision computation that rounds the state once
    per collision; the spread of such runs around the exact one measures how
    much the scene itself amplifies rounding (its conditioning). The time is
    not jittered: heyoka carries it in double-length arithmetic.

    Returns a
    :class:`ReferenceRun`; its status is ``max_collisions``, ``t_end`` (no
    further collision before t_end), ``contact`` (the law left two bodies
    without separation, which is not modelled) or ``inconsistent`` (the
    law's outgoing rates still close the gap, possible for the rolling law
    with unequal radii: u = c phi' with different c).
    """
    if n_collisions < 0:
        raise ValueError("n_collisions must be >= 0")
    run = ReferenceRun()
    rng = random.Random(seed)
    with mpmath.workdps(dps + GUARD_DPS):
        g = mpmath.mpf(scene.g)
        R = mpmath.mpf(scene.track.radius)
        bodies = scene.bodies
        nb = len(bodies)
        k = mpmath.mpf(scene.law.restitution)
        law = scene.law.name
        t_end = mpmath.mpf(scene.run.t_end if t_end is None else t_end)
        rnd = (lambda x: mpmath.mpf(float(x))) if double_inputs else (lambda x: mpmath.mpf(x))
        a = [rnd(g / (mpmath.mpf(b.kappa) * (R - mpmath.mpf(b.radius)))) for b in bodies]
        pendulums = [
            ExactPendulum(a[n], rnd(scene.phi[n]), rnd(scene.dphi[n]), 0, dps + GUARD_DPS) for n in range(nb)
        ]
        pairs = []
        if nb >= 2:
            for n in range(nb):
                i, j = n, (n + 1) % nb
                offset = 2 * mpmath.pi if j == 0 else mpmath.mpf(0)
                beta = _contact_angle(R, mpmath.mpf(bodies[i].radius), mpmath.mpf(bodies[j].radius))
                pairs.append(_Pair(i, j, rnd(offset - beta)))
        variables = [_law_variables(law, R, b) for b in bodies] if pairs else []
        counter = [0]
        t = mpmath.mpf(0)
        while len(run.collisions) < n_collisions:
            best, best_pair = None, None
            for pair in pairs:
                limit = t_end if best is None else best
                root = _first_root(pair, pendulums, a, t, limit, dps, counter)
                if root is not None and (best is None or root < best):
                    best, best_pair = root, pair
            if best is None:
                run.status, run.message = "t_end", f"no collision before t_end = {mpmath.nstr(t_end, 17)}"
                break
            t = best
            i, j = best_pair.i, best_pair.j
            phi_i, dphi_i = pendulums[i].state(t)
            phi_j, dphi_j = pendulums[j].state(t)
            (c_i, M_i), (c_j, M_j) = variables[i], variables[j]
            out_i, out_j = apply_law(c_i, M_i, c_j, M_j, k, dphi_i, dphi_j)
            with mpmath.workdps(dps):
                run.collisions.append(
                    ReferenceCollision(
                        t=+t, i=i + 1, j=j + 1, q_i=+phi_i, q_j=+phi_j,
                        dq_i_before=+dphi_i, dq_j_before=+dphi_j,
                        dq_i_after=+out_i, dq_j_after=+out_j,
                    )
                )
            opening, tiny = out_j - out_i, mpmath.mpf(10) ** (-(dps // 2)) * abs(dphi_i - dphi_j)
            if opening <= tiny:
                where = f"collision {len(run.collisions)} at t = {mpmath.nstr(t, 17)}: bodies {i + 1} and {j + 1}"
                if opening < -tiny:
                    run.status = "inconsistent"
                    run.message = f"{where} still approach after the '{law}' law (they would overlap)"
                else:
                    run.status = "contact"
                    run.message = f"{where} do not separate after the law (persistent contact)"
                break
            if jitter:
                # Model of an ideal double-precision computation: one relative
                # rounding of size ~jitter on every quantity carried past the collision.
                def nudge(x):
                    return x * (1 + jitter * rng.gauss(0, 1))
                phi_i, phi_j, out_i, out_j = (nudge(x) for x in (phi_i, phi_j, out_i, out_j))
            # Only the two colliding bodies start a new pendulum arc; the
            # others keep theirs (no re-initialisation, no accumulated error).
            pendulums[i] = ExactPendulum(a[i], phi_i, out_i, t, dps + GUARD_DPS)
            pendulums[j] = ExactPendulum(a[j], phi_j, out_j, t, dps + GUARD_DPS)
        else:
            run.message = f"stopped after {n_collisions} collisions"
        run.pendulums = pendulums
        run.steps = counter[0]
    return run


def reference_collisions(scene, n_collisions: int, dps: int = 40, t_end=None, *, double_inputs: bool = False) -> list:
    """The first ``n_collisions`` collisions of ``scene`` as a list of :class:`ReferenceCollision`.

    Fewer are returned if the run reaches ``t_end`` (default: the scene's)
    or two bodies stop separating; use :func:`run_reference` for the reason
    and for ``double_inputs``.
    """
    return run_reference(scene, n_collisions, dps=dps, t_end=t_end, double_inputs=double_inputs).collisions


def reference_table(collisions) -> np.ndarray:
    """The collisions as a numpy structured array with the engine table's column names.

    Columns ``REFERENCE_COLUMNS`` (float64, n/i/j int64): compare with
    ``result.collision_table()`` column by column.
    """
    dtype = [(c, np.int64 if c in ("n", "i", "j") else np.float64) for c in REFERENCE_COLUMNS]
    table = np.zeros(len(collisions), dtype=dtype)
    for row, c in enumerate(collisions):
        table[row] = (row + 1,) + tuple(
            getattr(c, name) if name in ("i", "j") else float(getattr(c, name)) for name in REFERENCE_COLUMNS[1:]
        )
    return table


def compare_with_engine(engine_table: np.ndarray, collisions, columns=None) -> dict:
    """Per-row errors of an engine collision table against reference collisions.

    Returns a dict of numpy arrays over the common rows: ``same_pair`` (bool),
    ``t_rel`` (|t_e - t_ref| / |t_ref|, the error taken in mpmath against the
    reference value), and for each rate/position column ``<name>_abs``
    (absolute error, rad or rad/s) and ``<name>_rel`` (relative to the
    column's scale: max |reference value| over the rows compared).
    """
    columns = columns or ("q_i", "q_j", "dq_i_before", "dq_j_before", "dq_i_after", "dq_j_after")
    n = min(len(engine_table), len(collisions))
    out = {
        "same_pair": np.array(
            [int(engine_table["i"][r]) == collisions[r].i and int(engine_table["j"][r]) == collisions[r].j for r in range(n)],
            dtype=bool,
        )
    }
    with mpmath.workdps(40):
        out["t_rel"] = np.array(
            [float(abs(mpmath.mpf(float(engine_table["t"][r])) - collisions[r].t) / abs(collisions[r].t)) if collisions[r].t != 0
             else abs(float(engine_table["t"][r])) for r in range(n)]
        )
        for name in columns:
            ref = [getattr(collisions[r], name) for r in range(n)]
            err = np.array([float(abs(mpmath.mpf(float(engine_table[name][r])) - ref[r])) for r in range(n)])
            scale = max((float(abs(x)) for x in ref), default=1.0) or 1.0
            out[f"{name}_abs"] = err
            out[f"{name}_rel"] = err / scale
    return out
