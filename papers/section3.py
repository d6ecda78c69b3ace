"""Paper section 3: Table 1 (translation <-> rolling) and the worked examples a*, b*, c* of 3.6.

Run:  python papers/section3.py

Table 1 sets Newton's central collision of two bodies in translation
(masses m, velocities v; eqs. 1-5) beside the collision of two rolling balls
(inertias J_P about the rolling axes, rolling rates omega_P; eqs. 8-12, 15).
Each row is one formula in generic variables (M, u); here it is evaluated on a
sample state in both columns and checked against heyroll's laws
(NewtonCentreLaw on centre speeds, HedrihRollingLaw on rolling rates). Rows
are written in their correct form; where the printed table differs (outgoing
u_2 with 1 + M_1/M_2, energy change without its minus sign) the printed value
is shown too (see papers/ERRATA.md).

Examples a*, b*, c*: two solid balls of equal density with radius ratios
r2/r1 = 2, 3, 3/2, so J_P1/J_P2 = (r1/r2)^5 = 1/32, 1/243, 32/243, and the
outgoing-rate coefficients 1/(1 + J_P1/J_P2) and 1/(1 + J_P2/J_P1) are
32/33 & 1/33, 243/244 & 1/244, 243/275 & 32/275. They are computed here from
heyroll's bodies and law (outgoing, and the engine's impulse_map) in 256-bit
mpmath and compared with the paper's fractions to 40 digits.

Uses no integrator (heyoka is not called; note that ``import heyroll``
itself currently imports it).
"""

from __future__ import annotations

import sys
from fractions import Fraction

import mpmath

from heyroll.model._numbers import workprec
from heyroll.model.bodies import Body
from heyroll.model.laws import HedrihRollingLaw, NewtonCentreLaw, impulse_map, outgoing
from heyroll.model.tracks import CircleTrack

#: Agreement demanded between model values and the paper's fractions.
DIGITS = 40
TOL = mpmath.mpf(10) ** (-DIGITS)


# --- Table 1 rows, in generic variables: inertia M, velocity u ------------------------------


def row_conservation(M1, M2, u1, u2):
    """Row 'conservation': M1 u1 + M2 u2 (eq. 1 with m, v; eq. 8 with J_P, omega_P)."""
    return M1 * u1 + M2 * u2


def row_restitution(u1, u2, u1_out, u2_out):
    """Row 'restitution': k = (u2+ - u1+)/(u1 - u2) (eq. 2; eq. 9)."""
    return (u2_out - u1_out) / (u1 - u2)


def row_outgoing(M1, M2, u1, u2, k):
    """Row 'outgoing velocities', correct form (eqs. 3-4; 10-11)."""
    du = u1 - u2
    return u1 - (1 + k) / (1 + M1 / M2) * du, u2 + (1 + k) / (1 + M2 / M1) * du


def row_outgoing_as_printed(M1, M2, u1, u2, k):
    """Table 1 as printed: the second body's row has 1 + M1/M2 (should be 1 + M2/M1)."""
    du = u1 - u2
    return u1 - (1 + k) / (1 + M1 / M2) * du, u2 + (1 + k) / (1 + M1 / M2) * du


def row_impulse(M1, M2, u1, u2, k):
    """Row 'impulse': M1 (u1+ - u1) = -M1 M2/(M1 + M2) (1 + k)(u1 - u2) (eq. 5; eq. 12)."""
    return -M1 * M2 / (M1 + M2) * (1 + k) * (u1 - u2)


def row_energy_change(M1, M2, u1, u2, k):
    """Row 'kinetic energy change', correct form: -M1 M2/(2(M1+M2)) (1-k^2)(u1-u2)^2 (eqs. 15-16)."""
    return -M1 * M2 / (2 * (M1 + M2)) * (1 - k * k) * (u1 - u2) ** 2


def row_energy_change_as_printed(M1, M2, u1, u2, k):
    """Table 1 as printed (rolling column): the same without the minus sign."""
    return -row_energy_change(M1, M2, u1, u2, k)


def kinetic_energy(M1, M2, u1, u2):
    """E_k = 1/2 (M1 u1^2 + M2 u2^2) (eqs. 13-14)."""
    return (M1 * u1 * u1 + M2 * u2 * u2) / 2


def sample_state():
    """Two solid steel balls (r = 1/8 and 1/4 m) inside a 1 m circle, k = 7/10."""
    track = CircleTrack.of_radius(1)
    b1 = Body.of_shape("solid_sphere", Fraction(1, 8), density=7800)
    b2 = Body.of_shape("solid_sphere", Fraction(1, 4), density=7800)
    k = Fraction(7, 10)
    omega = (mpmath.mpf(3), mpmath.mpf(-1))  # rolling rates omega_P, rad/s
    return track, b1, b2, k, omega


def table1_columns():
    """Both columns of Table 1 on the sample state, as {column: {row: value(s)}}.

    The translation column uses the same two balls as point masses m moving
    with their centre speeds v = r omega_P (= (R - r) phi', eq. 22); the
    rolling column uses J_P and omega_P. Each column also holds what
    heyroll's law gives, for the check.
    """
    track, b1, b2, k, (w1, w2) = sample_state()
    columns = {}
    with workprec():
        for name, law in (("translation", NewtonCentreLaw(restitution=k)), ("rolling", HedrihRollingLaw(restitution=k))):
            v1, v2 = law.variables(b1, track.path_radius(b1)), law.variables(b2, track.path_radius(b2))
            M1, M2 = v1.inertia, v2.inertia
            # the same physical state in both columns: phi' = omega_P / ((R - r)/r)
            u1 = v1.scale * w1 / track.rolling_ratio(b1)
            u2 = v2.scale * w2 / track.rolling_ratio(b2)
            kk = law.restitution
            u1o, u2o = row_outgoing(M1, M2, u1, u2, kk)
            law_u1o, law_u2o = outgoing(law, b1, b2, u1, u2, track.path_radius(b1), track.path_radius(b2))
            columns[name] = {
                "inertia": (M1, M2),
                "incoming": (u1, u2),
                "conservation": (row_conservation(M1, M2, u1, u2), row_conservation(M1, M2, u1o, u2o)),
                "restitution": row_restitution(u1, u2, u1o, u2o),
                "outgoing": (u1o, u2o),
                "outgoing_law": (law_u1o, law_u2o),
                "outgoing_as_printed": row_outgoing_as_printed(M1, M2, u1, u2, kk),
                "impulse": (row_impulse(M1, M2, u1, u2, kk), M1 * (u1o - u1)),
                "energy_change": (
                    row_energy_change(M1, M2, u1, u2, kk),
                    kinetic_energy(M1, M2, u1o, u2o) - kinetic_energy(M1, M2, u1, u2),
                ),
                "energy_change_as_printed": row_energy_change_as_printed(M1, M2, u1, u2, kk),
                "k": kk,
            }
    return columns


def _close(a, b) -> bool:
    """Equal to within 2^-230 relative (model numbers carry 256 bits)."""
    with workprec():
        return abs(a - b) <= mpmath.mpf(2) ** (-230) * max(1, abs(a), abs(b))


def table1_checks(columns):
    """(row, column, ok) for every row of Table 1: each formula holds in both columns."""
    out = []
    for name, c in columns.items():
        (u1o, u2o), (l1, l2) = c["outgoing"], c["outgoing_law"]
        out += [
            ("conservation", name, _close(*c["conservation"])),
            ("restitution", name, _close(c["restitution"], c["k"])),
            ("outgoing = law", name, _close(u1o, l1) and _close(u2o, l2)),
            ("impulse", name, _close(*c["impulse"])),
            ("energy change", name, _close(*c["energy_change"])),
        ]
    return out


# --- Examples a*, b*, c* of section 3.6 ---------------------------------------------------------

#: (label, r2/r1, paper's J_P1/J_P2, paper's coefficient for omega_P1, for omega_P2)
PAPER_EXAMPLES = (
    ("a*", Fraction(2), Fraction(1, 32), Fraction(32, 33), Fraction(1, 33)),
    ("b*", Fraction(3), Fraction(1, 243), Fraction(243, 244), Fraction(1, 244)),
    ("c*", Fraction(3, 2), Fraction(32, 243), Fraction(243, 275), Fraction(32, 275)),
)


def to_fraction(x, max_denominator: int = 10**6) -> Fraction:
    """The simplest fraction within 10^-DIGITS of the mpmath number x (raises if none)."""
    with workprec():  # mpmath.mpf(x) would round x to the ambient precision
        man, exp = (x if isinstance(x, mpmath.mpf) else mpmath.mpf(x)).man_exp
    exact = Fraction(man) * Fraction(2) ** exp
    f = exact.limit_denominator(max_denominator)
    if abs(exact - f) > Fraction(1, 10**DIGITS):
        raise ValueError(f"{mpmath.nstr(x, 30)} is no fraction with denominator <= {max_denominator}")
    return f


def example_coefficients(r1=Fraction(1, 8), density=7800, R=1):
    """Model values for a*, b*, c*: {label: dict of mpf values and the paper's fractions}.

    a1, a2 are the coefficients in omega_P1+ = omega_P1 - a1 (1 + k)(omega_P1 - omega_P2),
    omega_P2+ = omega_P2 + a2 (1 + k)(omega_P1 - omega_P2): a1 = 1/(1 + J_P1/J_P2),
    a2 = 1/(1 + J_P2/J_P1). They are read off heyroll's law at k = 0 in two ways:
    from ``outgoing`` (paper form, eqs. 10-11) and from the engine's ``impulse_map``.
    """
    track = CircleTrack.of_radius(R)
    law = HedrihRollingLaw(restitution=0)
    results = {}
    with workprec():
        for label, ratio, p_ratio, p_a1, p_a2 in PAPER_EXAMPLES:
            b1 = Body.of_shape("solid_sphere", r1, density=density)
            b2 = Body.of_shape("solid_sphere", r1 * ratio, density=density)
            J1, J2 = b1.rolling_inertia(), b2.rolling_inertia()
            w1o, w2o = outgoing(law, b1, b2, mpmath.mpf(1), mpmath.mpf(0), track.path_radius(b1), track.path_radius(b2))
            imap = impulse_map(law, b1, b2, track.path_radius(b1), track.path_radius(b2))
            c1, c2 = track.rolling_ratio(b1), track.rolling_ratio(b2)
            results[label] = {
                "radius_ratio": ratio,
                "inertia_ratio": J1 / J2,
                "a1_outgoing": 1 - w1o,
                "a2_outgoing": w2o,
                "a1_impulse_map": imap.a_i,
                "a2_impulse_map": imap.a_j * c2 / c1,
                "paper": (p_ratio, p_a1, p_a2),
            }
    return results


def example_checks(results):
    """(label, quantity, model Fraction, paper Fraction, ok) for each example."""
    out = []
    for label, r in results.items():
        p_ratio, p_a1, p_a2 = r["paper"]
        for quantity, value, paper in (
            ("J_P1/J_P2", r["inertia_ratio"], p_ratio),
            ("1/(1+J_P1/J_P2)  [outgoing]", r["a1_outgoing"], p_a1),
            ("1/(1+J_P1/J_P2)  [impulse_map]", r["a1_impulse_map"], p_a1),
            ("1/(1+J_P2/J_P1)  [outgoing]", r["a2_outgoing"], p_a2),
            ("1/(1+J_P2/J_P1)  [impulse_map]", r["a2_impulse_map"], p_a2),
        ):
            with workprec():
                ok = abs(value - mpmath.mpf(paper.numerator) / paper.denominator) <= TOL
            out.append((label, quantity, to_fraction(value), paper, ok))
    return out


def main() -> int:
    all_ok = True
    print("Table 1: translation (m, v_C)  <->  rolling (J_P, omega_P); sample state:")
    track, b1, b2, k, (w1, w2) = sample_state()
    print(f"  track R = {mpmath.nstr(track.radius, 6)} m; ball 1: {b1.describe()}; ball 2: {b2.describe()}")
    print(f"  omega_P = ({w1}, {w2}) rad/s, k = {k}\n")
    cols = table1_columns()
    fmt = lambda x: mpmath.nstr(x, 12)  # noqa: E731
    pair = lambda p: f"({fmt(p[0])}, {fmt(p[1])})"  # noqa: E731
    t, r = cols["translation"], cols["rolling"]
    rows = [
        ("inertia (m | J_P)", pair(t["inertia"]), pair(r["inertia"])),
        ("incoming (v | omega_P)", pair(t["incoming"]), pair(r["incoming"])),
        ("sum before, after (1 | 8)", pair(t["conservation"]), pair(r["conservation"])),
        ("restitution (2 | 9)", fmt(t["restitution"]), fmt(r["restitution"])),
        ("outgoing (3-4 | 10-11)", pair(t["outgoing"]), pair(r["outgoing"])),
        ("  printed Table 1", pair(t["outgoing_as_printed"]), pair(r["outgoing_as_printed"])),
        ("impulse (5 | 12), check", pair(t["impulse"]), pair(r["impulse"])),
        ("dE_k (15), check", pair(t["energy_change"]), pair(r["energy_change"])),
        ("  printed Table 1", fmt(t["energy_change_as_printed"]), fmt(r["energy_change_as_printed"])),
    ]
    w = max(len(x[0]) for x in rows)
    print(f"  {'row':<{w}}  {'translation':<34}  rolling")
    for name, a, b in rows:
        print(f"  {name:<{w}}  {a:<34}  {b}")
    print()
    for row, col, ok in table1_checks(cols):
        all_ok &= bool(ok)
        print(f"  [{'ok' if ok else 'FAIL'}] {row} holds in the {col} column")
    print("  (printed Table 1 rows differ: see papers/ERRATA.md, table1_* entries)\n")

    print("Section 3.6 examples: solid balls of equal density, J_P1/J_P2 = (r1/r2)^5")
    print(f"  {'':3} {'r2/r1':>5}  {'quantity':<31} {'heyroll':>9}  {'paper':>9}")
    results = example_coefficients()
    for label, quantity, model, paper, ok in example_checks(results):
        all_ok &= bool(ok)
        ratio = results[label]["radius_ratio"]
        print(f"  {label:3} {str(ratio):>5}  {quantity:<31} {str(model):>9}  {str(paper):>9}  "
              f"{'agree to ' + str(DIGITS) + ' digits' if ok else 'DISAGREE'}")
    print("\nall checks passed" if all_ok else "\nSOME CHECKS FAILED")
    return 0 if all_ok else 1


if __name__ == "__main__":
    sys.exit(main())
