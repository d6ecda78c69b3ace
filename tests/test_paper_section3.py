"""Paper section 3: Table 1 rows and the worked examples a*, b*, c* of 3.6 (via papers/section3.py)."""

from __future__ import annotations

import importlib.util
import random
from fractions import Fraction
from pathlib import Path

import mpmath
import pytest

from heyroll.model._numbers import workprec
from heyroll.model.bodies import Body
from heyroll.model.laws import HedrihRollingLaw, NewtonCentreLaw, collision_impulse, kinetic_energy_change, outgoing
from heyroll.model.tracks import CircleTrack

SCRIPT = Path(__file__).resolve().parents[1] / "papers" / "section3.py"


def _load_script():
    spec = importlib.util.spec_from_file_location("paper_section3", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


S3 = _load_script()
EXACT = {  # label: (r2/r1, J_P1/J_P2, 1/(1 + J_P1/J_P2), 1/(1 + J_P2/J_P1))
    "a*": (Fraction(2), Fraction(1, 32), Fraction(32, 33), Fraction(1, 33)),
    "b*": (Fraction(3), Fraction(1, 243), Fraction(243, 244), Fraction(1, 244)),
    "c*": (Fraction(3, 2), Fraction(32, 243), Fraction(243, 275), Fraction(32, 275)),
}


def as_mpf(f: Fraction):
    return mpmath.mpf(f.numerator) / f.denominator


@pytest.mark.parametrize("label", sorted(EXACT))
def test_example_coefficients_exact(label):
    """a*, b*, c*: the model's coefficients equal the paper's fractions to 2^-240."""
    ratio, j_ratio, a1, a2 = EXACT[label]
    r = S3.example_coefficients()[label]
    assert r["radius_ratio"] == ratio
    with workprec():
        tol = mpmath.mpf(2) ** (-240)
        assert abs(r["inertia_ratio"] - as_mpf(j_ratio)) <= tol
        for key in ("a1_outgoing", "a1_impulse_map"):
            assert abs(r[key] - as_mpf(a1)) <= tol
        for key in ("a2_outgoing", "a2_impulse_map"):
            assert abs(r[key] - as_mpf(a2)) <= tol
    # the two coefficients add up to 1 and the fractions are the paper's
    assert a1 + a2 == 1
    assert a1 == 1 / (1 + j_ratio) and a2 == 1 / (1 + 1 / j_ratio)
    assert j_ratio == (1 / ratio) ** 5


@pytest.mark.parametrize("label", sorted(EXACT))
def test_example_coefficients_independent_of_size_and_density(label):
    """Only the radius ratio matters for equal densities (J_P ~ rho r^5)."""
    base = S3.example_coefficients()[label]
    other = S3.example_coefficients(r1=Fraction(3, 100), density="2700.5", R=7)[label]
    with workprec():
        for key in ("inertia_ratio", "a1_outgoing", "a2_outgoing", "a1_impulse_map", "a2_impulse_map"):
            assert abs(base[key] - other[key]) <= mpmath.mpf(2) ** (-230)


def test_example_checks_all_pass_and_fractions_recovered():
    checks = S3.example_checks(S3.example_coefficients())
    assert len(checks) == 15
    for _label, _quantity, model, paper, ok in checks:
        assert ok and model == paper


def test_table1_rows_hold_in_both_columns():
    """Table 1 (corrected): every row is the same formula in (m, v) and in (J_P, omega_P)."""
    checks = S3.table1_checks(S3.table1_columns())
    assert {(row, col) for row, col, _ in checks} == {
        (row, col)
        for row in ("conservation", "restitution", "outgoing = law", "impulse", "energy change")
        for col in ("translation", "rolling")
    }
    assert all(ok for _, _, ok in checks)


def test_table1_printed_rows_differ_from_correct_rows():
    """The printed outgoing u2 row and the printed energy rows are not the correct ones (ERRATA)."""
    cols = S3.table1_columns()
    for c in cols.values():
        assert c["outgoing_as_printed"][0] == c["outgoing"][0]
        assert abs(c["outgoing_as_printed"][1] - c["outgoing"][1]) > 1e-3
        with workprec():  # (unary minus rounds to the ambient precision)
            assert c["energy_change_as_printed"] == -c["energy_change"][0] > 0


@pytest.mark.parametrize("seed", range(5))
def test_table1_rows_match_heyroll_laws_on_random_states(seed):
    """Rows of Table 1 against the model: Newton on (m, v_C), hedrih on (J_P, omega_P)."""
    rng = random.Random(seed)
    track = CircleTrack.of_radius(1)
    shapes = ("solid_sphere", "hollow_sphere", "disk", "ring")
    b1 = Body.of_shape(rng.choice(shapes), Fraction(rng.randint(1, 45), 100), mass=rng.randint(1, 100))
    b2 = Body.of_shape(rng.choice(shapes), Fraction(rng.randint(1, 45), 100), mass=rng.randint(1, 100))
    k = Fraction(rng.randint(0, 100), 100)
    with workprec():
        for law in (NewtonCentreLaw(restitution=k), HedrihRollingLaw(restitution=k)):
            M1, M2 = law.variables(b1, track.path_radius(b1)).inertia, law.variables(b2, track.path_radius(b2)).inertia
            u1, u2 = mpmath.mpf(rng.uniform(-5, 5)), mpmath.mpf(rng.uniform(-5, 5))
            kk = law.restitution
            o1, o2 = outgoing(law, b1, b2, u1, u2, track.path_radius(b1), track.path_radius(b2))
            r1, r2 = S3.row_outgoing(M1, M2, u1, u2, kk)
            tol = mpmath.mpf(2) ** (-230) * (abs(u1) + abs(u2)) * max(1, M1, M2)
            assert abs(o1 - r1) <= tol and abs(o2 - r2) <= tol
            assert abs(S3.row_conservation(M1, M2, u1, u2) - S3.row_conservation(M1, M2, o1, o2)) <= tol
            assert abs(S3.row_restitution(u1, u2, o1, o2) - kk) <= mpmath.mpf(2) ** (-200)
            assert abs(S3.row_impulse(M1, M2, u1, u2, kk) - collision_impulse(M1, M2, kk, u1 - u2)) <= tol
            assert abs(
                S3.row_energy_change(M1, M2, u1, u2, kk) - kinetic_energy_change(M1, M2, kk, u1 - u2)
            ) <= tol * (abs(u1) + abs(u2))


def test_script_runs_and_passes(capsys):
    assert S3.main() == 0
    out = capsys.readouterr().out
    for text in ("32/33", "1/33", "243/244", "1/244", "243/275", "32/275", "all checks passed"):
        assert text in out
