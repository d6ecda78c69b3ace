"""Simultaneous impulses as a linear complementarity problem, for the table and the circle.

Find L >= 0 with w = A L + b >= 0 and L . w = 0: A the contacts' Delassus matrix (symmetric positive
semi-definite, or such a matrix scaled by positive diagonals on either side, which has the same
solutions and the same Gauss-Seidel iterates in the scaled variables), b the separation rates each
contact must reach. Exactly, by trying active sets smallest first, up to MAX_SIMULTANEOUS contacts;
beyond, by projected Gauss-Seidel. In the entries' own number type, to a tolerance of the run's
(:func:`relative_tolerance`).
"""

from __future__ import annotations

from itertools import combinations

#: Contacts whose active set 'impulses' searches over all subsets (2^m of them); more go to projected
#: Gauss-Seidel (a rack of 15 balls touching: 30 contacts).
MAX_SIMULTANEOUS = 8
#: Sweeps of projected Gauss-Seidel at most.
GAUSS_SEIDEL_SWEEPS = 100_000


def relative_tolerance(precision):
    """The solution's relative tolerance in ``precision``'s type: 1e-12 in double, as many ulps in the others
    (a fixed 1e-12 stopped quad's Gauss-Seidel 1e-14 short: a 21-ball break's solution gained 5.9e-15 of
    its energy, past quad's acceptance, and went one contact at a time where double's went at once: review)."""
    return precision.number(1e-12 * (precision.epsilon / 2.0**-52))


def complementarity(a, b, zero, relative=1e-12):
    """L >= 0 with w = A L + b >= 0 and L . w = 0 (A symmetric PSD): exactly, by trying active sets
    smallest first, for up to MAX_SIMULTANEOUS contacts; beyond, by projected Gauss-Seidel sweeps.
    ``relative``: the slack of the inequalities, of the largest |b| (:func:`relative_tolerance`)."""
    m = len(b)
    if all(x >= zero for x in b):
        return [zero] * m
    if m > MAX_SIMULTANEOUS:
        return _gauss_seidel(a, b, zero, relative / 100)
    slack = max(abs(x) for x in b) * relative if m else zero
    for size in range(1, m + 1):
        for subset in combinations(range(m), size):
            lam_s = _solve([[a[p][q] for q in subset] for p in subset], [-b[p] for p in subset])
            if lam_s is None or any(x < -slack for x in lam_s):
                continue
            lam = [zero] * m
            for p, x in zip(subset, lam_s):
                lam[p] = x if x > zero else zero
            w = [sum((a[p][q] * lam[q] for q in range(m)), zero) + b[p] for p in range(m)]
            if all(w[p] >= -slack for p in range(m) if p not in subset):
                return lam
    return None


def _solve(matrix, rhs):
    """Gaussian elimination with partial pivoting in the entries' own type; None if singular."""
    n = len(rhs)
    m = [row[:] + [r] for row, r in zip(matrix, rhs)]
    scale = max((abs(x) for row in matrix for x in row), default=0)
    for col in range(n):
        pivot = max(range(col, n), key=lambda r: abs(m[r][col]))
        if not abs(m[pivot][col]) > scale * 1e-12:
            return None
        m[col], m[pivot] = m[pivot], m[col]
        for r in range(col + 1, n):
            f = m[r][col] / m[col][col]
            for c in range(col, n + 1):
                m[r][c] = m[r][c] - f * m[col][c]
    x = [None] * n
    for r in range(n - 1, -1, -1):
        total = m[r][n]
        for c in range(r + 1, n):
            total = total - m[r][c] * x[c]
        x[r] = total / m[r][r]
    return x


def _gauss_seidel(a, b, zero, relative):
    """Projected Gauss-Seidel for the complementarity problem: converges for a symmetric PSD A with
    positive diagonal; stops when a sweep changes no impulse by more than ``relative`` of the largest."""
    m = len(b)
    lam = [zero] * m
    for _ in range(GAUSS_SEIDEL_SWEEPS):
        change = zero
        for p in range(m):
            if not a[p][p] > zero:
                continue
            w = b[p]
            for q in range(m):
                w = w + a[p][q] * lam[q]
            new = lam[p] - w / a[p][p]
            if new < zero:
                new = zero
            step = abs(new - lam[p])
            if step > change:
                change = step
            lam[p] = new
        largest = max(lam)
        if not change > largest * relative:
            return lam
    return None
