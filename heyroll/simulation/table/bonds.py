"""Contacts held closed on the table (bonds) and the forces that hold a cluster of them.

A bond is a contact that stays closed: two balls pressed together (the limit of their accumulating impacts,
k < 1, or of friction driving one into the other) or, for a ball that is also pressed against another, the
cushion it rides. Bonds are tuples: ``("pair", i, j)`` (i < j) and ``("wall", k, w)``. Bonds that share a ball
form a cluster (a chain of balls pressed together, a pair pressed into a cushion, a row in a corner); the
contact forces of a cluster are coupled and solved together.

Each bond e has a constraint C_e = 0 and, on every ball k it touches, a direction n_ek along which its
multiplier lambda_e pushes (per unit mobility w_k: a_k = f_k + w_k sum_e lambda_e n_ek, f_k the ball's own
acceleration, its friction):

* pair (i, j), dc = c_j - c_i: C = |dc|^2 - (R_i + R_j)^2, n_i = -dc, n_j = dc (pushing apart), and
  C''/2 = |dv|^2 + sum_k n_k . a_k;
* wall (k, w), g the gap of ball k to wall w (> 0 outside the table): C = g, n_k = -grad g (into the table), and
  -C'' = -v^T H v + n_k . a_k.

Holding C'' = -2 alpha C' - alpha^2 C (Baumgarte's correction of round-off drift, as for a single rider) gives
the linear system A lambda = r - J f with A_ef = sum over the balls k that e and f share of
w_k n_ek . n_fk = J W J^T, symmetric positive definite while the bonds' directions are independent: solved by
elimination without pivoting (:func:`solve`), on heyoka expressions in the compiled equations and on numbers
in the driver's decisions. Paper section 7 treats single impacts only; a cluster's forces are the classical
unilateral-contact (Lagrange multiplier) solution with the active set kept by events: a bond lets go where
its multiplier without Baumgarte's terms falls through 0.
"""

from __future__ import annotations

import itertools

#: The most bonds in one cluster: elimination on expressions grows as m^3 (a rack pressed together is refused
#: with this number in the message rather than compiled for minutes).
MAX_CLUSTER_BONDS = 8


def bond_balls(bond: tuple) -> tuple:
    """The balls a bond touches."""
    return (bond[1], bond[2]) if bond[0] == "pair" else (bond[1],)


def clusters(bonds) -> list:
    """The bonds grouped into clusters (bonds that share a ball, transitively), each sorted."""
    groups: list = []
    for bond in sorted(bonds):
        balls = set(bond_balls(bond))
        joined = [g for g in groups if g[1] & balls]
        merged = ([bond], balls)
        for g in joined:
            groups.remove(g)
            merged = (merged[0] + g[0], merged[1] | g[1])
        groups.append(merged)
    return [sorted(g[0]) for g in groups]


def cluster_of(bonds, ball: int) -> list:
    """The cluster of ``bonds`` that holds ``ball`` ([] if none)."""
    for group in clusters(bonds):
        if any(ball in bond_balls(b) for b in group):
            return group
    return []


def topology(bonds, wall_shape) -> tuple:
    """The run's bonds as a shape that does not name the balls: what the compiled system depends on, so that
    one compiled system serves every set of bonds of the same shape (a chain of two pairs anywhere on the table;
    a 16-ball break met 60 different sets, each compiled for 0.1-1 s). Returns (local bonds, members, slots):
    the local bonds ``("pair", a, b)`` (a < b) and ``("wall", a, n)`` (n = ``wall_shape(ball, wall)``, the
    number of the wall's constants: its gap's form) over local members 0, 1, ...; ``members`` the actual ball of
    each local member; ``slots`` the actual bond of each local bond. Each cluster is labelled so that its
    local bonds are least (all orders of up to 6 members tried: isomorphic clusters share a shape), the
    clusters in the order of their forms."""
    labelled = []
    for group in clusters(bonds):
        balls = sorted({k for bond in group for k in bond_balls(bond)})
        orders = itertools.permutations(balls) if len(balls) <= 6 else [_first_seen(group)]
        best = None
        for order in orders:
            label = {k: n for n, k in enumerate(order)}
            form = sorted((_local(bond, label, wall_shape), bond) for bond in group)
            key = tuple(f for f, _ in form)
            if best is None or key < best[0]:
                best = (key, form, order)
        labelled.append(best)
    labelled.sort(key=lambda item: item[0])
    local, members, slots = [], [], []
    for key, form, order in labelled:
        shift = len(members)
        members += list(order)
        for (kind, a, b), bond in form:
            local.append((kind, a + shift, b + shift) if kind == "pair" else (kind, a + shift, b))
            slots.append(bond)
    return tuple(local), tuple(members), tuple(slots)


def _local(bond: tuple, label: dict, wall_shape) -> tuple:
    if bond[0] == "pair":
        a, b = sorted((label[bond[1]], label[bond[2]]))
        return ("pair", a, b)
    return ("wall", label[bond[1]], wall_shape(bond[1], bond[2]))


def _first_seen(group: list) -> list:
    order: list = []
    for bond in group:
        for k in bond_balls(bond):
            if k not in order:
                order.append(k)
    return order


def bond_matrix(directions: list, mobility: dict) -> list:
    """A = J W J^T of bonds with ``directions`` (per bond {ball: (nx, ny)}) and per-ball ``mobility``; None where
    two bonds share no ball (a structural zero, kept out of the expressions)."""
    m = len(directions)
    matrix = [[None] * m for _ in range(m)]
    for e in range(m):
        for f in range(e, m):
            total = None
            for k, (ex, ey) in directions[e].items():
                if k in directions[f]:
                    fx, fy = directions[f][k]
                    term = mobility[k] * (ex * fx + ey * fy)
                    total = term if total is None else total + term
            matrix[e][f] = matrix[f][e] = total
    return matrix


def _eliminate(matrix: list, right_sides: list) -> tuple:
    """Gaussian elimination without pivoting, forward: (the upper triangle, its pivots on the diagonal; the right
    sides carried along). None entries are zero."""
    m = len(matrix)
    a = [row[:] for row in matrix]
    bs = [list(b) for b in right_sides]
    for p in range(m):
        inverse = 1 / a[p][p]
        for i in range(p + 1, m):
            if a[i][p] is None:
                continue
            factor = a[i][p] * inverse
            for j in range(p + 1, m):
                if a[p][j] is not None:
                    a[i][j] = -factor * a[p][j] if a[i][j] is None else a[i][j] - factor * a[p][j]
            for b in bs:
                b[i] = b[i] - factor * b[p]
    return a, bs


def solve(matrix: list, right_sides: list) -> list:
    """Solutions of ``matrix`` x = b for each b of ``right_sides``: Gaussian elimination without pivoting (the
    matrix is symmetric positive definite), None entries zero. Works on any numbers with + - * / (heyoka
    expressions, floats, the run's type)."""
    m = len(matrix)
    a, bs = _eliminate(matrix, right_sides)
    solutions = []
    for b in bs:
        x = [None] * m
        for i in reversed(range(m)):
            total = b[i]
            for j in range(i + 1, m):
                if a[i][j] is not None:
                    total = total - a[i][j] * x[j]
            x[i] = total / a[i][i]
        solutions.append(x)
    return solutions


def independent(matrix: list, tolerance: float = 2.0**-30) -> bool:
    """The bonds' directions are independent: every pivot of the elimination of A = J W J^T (floats) above
    ``tolerance`` times its diagonal entry. Dependent bonds (three balls racked into a 60 degree corner: seven
    contacts on six degrees of freedom) leave the forces undetermined and the elimination divides by round-off."""
    floats = [[None if v is None else float(v) for v in row] for row in matrix]
    try:
        a, _ = _eliminate(floats, [])
    except ZeroDivisionError:  # a pivot of exactly 0
        return False
    return all(a[p][p] > tolerance * floats[p][p] for p in range(len(matrix)))


def complementary(matrix: list, right: list) -> list:
    """The lambda >= 0 with w = A lambda - b >= 0 and lambda_e w_e = 0 for every bond (floats; A symmetric positive
    definite: one solution), by Murty's principal pivoting (the least index that breaks a condition changes side;
    finite for such A). Bonds with lambda 0 let go (their contacts open or stay closed without force). Without
    convergence in 64 m pivots (round-off cycling) the bonds whose equality solution pulls get 0."""
    m = len(right)
    active = list(range(m))
    for _ in range(64 * m + 1):
        lam = [0.0] * m
        if active:
            sub = [[matrix[i][j] for j in active] for i in active]
            for e, value in zip(active, solve(sub, [[right[i] for i in active]])[0]):
                lam[e] = value
        wrong = None
        for e in range(m):
            opening = sum(matrix[e][f] * lam[f] for f in range(m) if matrix[e][f] is not None) - right[e]
            if (e in active and lam[e] < 0) or (e not in active and opening < 0):
                wrong = e
                break
        if wrong is None:
            return lam
        active = sorted(set(active) ^ {wrong})
    lam = solve(matrix, [right])[0]
    return [value if value > 0 else 0.0 for value in lam]


def pushes(directions: list, mobility: dict, multipliers: list) -> dict:
    """Per ball, the acceleration its bonds give it, w_k sum_e lambda_e n_ek, as (ax, ay)."""
    out: dict = {}
    for n, lam in zip(directions, multipliers):
        for k, (nx, ny) in n.items():
            ax, ay = lam * mobility[k] * nx, lam * mobility[k] * ny
            if k in out:
                out[k] = (out[k][0] + ax, out[k][1] + ay)
            else:
                out[k] = (ax, ay)
    return out


def correction(directions: list, mobility: dict, right: list) -> dict:
    """Per ball, w_k sum_e mu_e n_ek with A mu = ``right``: the change of position (right: the bonds' errors) or
    of velocity (right: their opening speeds, negated) that corrects every bond of a cluster at once."""
    mu, = solve(bond_matrix(directions, mobility), [right])
    return pushes(directions, mobility, mu)


def free_work(directions: list, free: dict) -> list:
    """Per bond, J f = sum_k n_ek . f_k of the balls' own accelerations ``free`` ({ball: (fx, fy)})."""
    out = []
    for n in directions:
        total = None
        for k, (nx, ny) in n.items():
            fx, fy = free[k]
            term = nx * fx + ny * fy
            total = term if total is None else total + term
        out.append(total)
    return out
