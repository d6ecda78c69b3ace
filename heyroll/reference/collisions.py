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

import mpmath
import numpy as np

from .pendulum import GUARD_DPS, ExactPendulum

#: Columns of :func:`reference_table`, a subset of the engine's collision table.
REFERENCE_COLUMNS = (
    "n", "t", "i", "j", "phi_i", "phi_j",
    "dphi_i_before", "dphi_j_before", "dphi_i_after", "dphi_j_after",
)

#: Safety cap on the safe steps spent looking for one root of one gap.
MAX_STEPS_PER_ROOT = 200_000


@dataclass(frozen=True)
class ReferenceCollision:
    """One collision: time, bodies (numbered from 1, i clockwise of j), positions and rates."""

    t: mpmath.mpf
    i: int
    j: int
    phi_i: mpmath.mpf
    phi_j: mpmath.mpf
    dphi_i_before: mpmath.mpf
    dphi_j_before: mpmath.mpf
    dphi_i_after: mpmath.mpf
    dphi_j_after: mpmath.mpf


@dataclass
class ReferenceRun:
    """A reference run: collisions, why it stopped, and the final pendulums."""

    collisions: list = field(default_factory=list)
    status: str = "max_collisions"  # max_collisions | t_end | contact
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
    """Earliest t in [t_start, t_limit] where the pair's gap reaches 0 while closing, or None."""
    pi_, pj_ = pendulums[pair.i], pendulums[pair.j]
    G2 = a[pair.i] + a[pair.j]
    tol_gap = mpmath.mpf(10) ** (-(dps // 3))
    tol_t = mpmath.mpf(10) ** (-(dps + 3))

    def gap(t):
        phi_i, dphi_i = pi_.state(t)
        phi_j, dphi_j = pj_.state(t)
        return phi_j + pair.constant - phi_i, dphi_j - dphi_i

    t = t_start
    for _ in range(MAX_STEPS_PER_ROOT):
        counter[0] += 1
        g, gp = gap(t)
        if gp < 0 and g <= tol_gap:
            return _polish(gap, t, tol_t)
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


def _polish(gap, t, tol_t):
    """Newton's method on a closing gap, from a point just before the root."""
    for _ in range(60):
        g, gp = gap(t)
        if gp >= 0:
            raise RuntimeError(f"gap stopped closing while polishing a root at t = {mpmath.nstr(t, 17)}")
        step = g / gp
        t = t - step
        if abs(step) <= tol_t * (1 + abs(t)):
            return t
    raise RuntimeError(f"Newton's method did not converge on a root near t = {mpmath.nstr(t, 17)}")


def run_reference(scene, n_collisions: int, dps: int = 40, t_end=None) -> ReferenceRun:
    """The first ``n_collisions`` collisions of ``scene`` (stopping at ``t_end``).

    ``t_end`` defaults to the scene's run setting. Returns a
    :class:`ReferenceRun`; its status is ``max_collisions``, ``t_end`` (no
    further collision before t_end) or ``contact`` (the law left two bodies
    without separation, which is not modelled).
    """
    if n_collisions < 0:
        raise ValueError("n_collisions must be >= 0")
    run = ReferenceRun()
    with mpmath.workdps(dps + GUARD_DPS):
        g = mpmath.mpf(scene.g)
        R = mpmath.mpf(scene.track.radius)
        bodies = scene.bodies
        nb = len(bodies)
        k = mpmath.mpf(scene.law.restitution)
        law = scene.law.name
        t_end = mpmath.mpf(scene.run.t_end if t_end is None else t_end)
        a = [g / (mpmath.mpf(b.kappa) * (R - mpmath.mpf(b.radius))) for b in bodies]
        pendulums = [
            ExactPendulum(a[n], scene.phi[n], scene.dphi[n], 0, dps + GUARD_DPS) for n in range(nb)
        ]
        pairs = []
        if nb >= 2:
            for n in range(nb):
                i, j = n, (n + 1) % nb
                offset = 2 * mpmath.pi if j == 0 else mpmath.mpf(0)
                beta = _contact_angle(R, mpmath.mpf(bodies[i].radius), mpmath.mpf(bodies[j].radius))
                pairs.append(_Pair(i, j, offset - beta))
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
                        t=+t, i=i + 1, j=j + 1, phi_i=+phi_i, phi_j=+phi_j,
                        dphi_i_before=+dphi_i, dphi_j_before=+dphi_j,
                        dphi_i_after=+out_i, dphi_j_after=+out_j,
                    )
                )
            if out_j - out_i <= mpmath.mpf(10) ** (-dps // 2) * abs(dphi_i - dphi_j):
                run.status = "contact"
                run.message = (
                    f"collision {len(run.collisions)} at t = {mpmath.nstr(t, 17)}: bodies {i + 1} and {j + 1} "
                    "do not separate after the law"
                )
                break
            # Only the two colliding bodies start a new pendulum arc; the
            # others keep theirs (no re-initialisation, no accumulated error).
            pendulums[i] = ExactPendulum(a[i], phi_i, out_i, t, dps + GUARD_DPS)
            pendulums[j] = ExactPendulum(a[j], phi_j, out_j, t, dps + GUARD_DPS)
        else:
            run.message = f"stopped after {n_collisions} collisions"
        run.pendulums = pendulums
        run.steps = counter[0]
    return run


def reference_collisions(scene, n_collisions: int, dps: int = 40, t_end=None) -> list:
    """The first ``n_collisions`` collisions of ``scene`` as a list of :class:`ReferenceCollision`.

    Fewer are returned if the run reaches ``t_end`` (default: the scene's)
    or two bodies stop separating; use :func:`run_reference` for the reason.
    """
    return run_reference(scene, n_collisions, dps=dps, t_end=t_end).collisions


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
    columns = columns or ("phi_i", "phi_j", "dphi_i_before", "dphi_j_before", "dphi_i_after", "dphi_j_after")
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
