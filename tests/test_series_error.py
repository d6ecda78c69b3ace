"""The paper's series (54)-(55) against Legendre's F, and its first-collision method (56)=(57).

Convergence is checked by fitting the error against the order, not at one
order: log err = c + N log rho_fit + alpha log N, with rho_fit compared to the
theoretical ratio max(u^2, k^2 u^2) (geometric) and, at a turning point,
log err against log N (algebraic, slope -1/2).
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

import heyroll
from heyroll.analysis.series_error import (
    LIBRATION,
    ROTATION,
    convergence_ratio,
    exact_integral,
    paper_method_first_collision,
    series_error_map,
    series_error_maps,
    series_error_table,
    series_integral,
)
from heyroll.interfaces.validation_figures import series_error_figure
from heyroll.reference.series import exact_time_integral, paper_series_as_printed, paper_series_corrected

from conftest import EXAMPLE


def _errors(u, k2, orders, dps=60):
    with mpmath.workdps(dps):
        exact = exact_integral(u, k2)
        return np.array([float(abs(series_integral(n, u, k2) - exact) / exact) for n in orders])


def _geometric_fit(orders, errors):
    """Least squares of log err = c + N log rho + alpha log N; returns (rho, alpha)."""
    N = np.asarray(orders, dtype=float)
    A = np.column_stack([np.ones_like(N), N, np.log(N)])
    coef, *_ = np.linalg.lstsq(A, np.log(errors), rcond=None)
    return math.exp(coef[1]), coef[2]


# ----------------------------------------------------------------------------- the series alone


def test_exact_integral_matches_reference_and_turning_point():
    with mpmath.workdps(40):
        for amp in (0.3, 1.5, 3.0):
            k2 = 1 / mpmath.sin(mpmath.mpf(amp) / 2) ** 2
            u = mpmath.sin(mpmath.mpf(amp) / 3)
            assert abs(exact_integral(u, k2) - exact_time_integral(u, k2).real) < mpmath.mpf(10) ** -35
            # At the turning point: K(1/k^2)/k (the quarter period times sqrt(C)/2).
            s = mpmath.sin(mpmath.mpf(amp) / 2)
            assert abs(exact_integral(s, k2) - mpmath.ellipk(s**2) * s) < mpmath.mpf(10) ** -35
        assert abs(exact_integral(mpmath.mpf("0.4"), "0.3") - mpmath.ellipf(mpmath.asin(mpmath.mpf("0.4")), "0.3")) < 1e-35


@pytest.mark.parametrize(
    "regime, u, k2, expected",
    [
        # libration, amplitude 60 deg, phi = 0.6 phi_max: rho = k^2 u^2 = sin^2(18 deg)/sin^2(30 deg) ~ 0.382
        (LIBRATION, math.sin(math.radians(18)), 1 / math.sin(math.radians(30)) ** 2, "k2u2"),
        # libration, amplitude 150 deg, phi = 0.8 phi_max: rho = k^2 u^2 ~ 0.71
        (LIBRATION, math.sin(math.radians(60)), 1 / math.sin(math.radians(75)) ** 2, "k2u2"),
        # rotation k^2 = 0.5, phi = 0.7 pi: rho = u^2 ~ 0.794 (k^2 u^2 ~ 0.40 is the smaller ratio)
        (ROTATION, math.sin(0.35 * math.pi), 0.5, "u2"),
        # rotation k^2 = 0.9, phi = 0.4 pi: rho = u^2 ~ 0.345
        (ROTATION, math.sin(0.2 * math.pi), 0.9, "u2"),
    ],
)
def test_order_convergence_is_geometric_at_the_predicted_rate(regime, u, k2, expected):
    rho = u * u * k2 if expected == "k2u2" else u * u
    assert abs(rho - float(convergence_ratio(u, k2))) < 1e-12
    orders = list(range(8, 41, 2))
    errors = _errors(u, k2, orders)
    assert np.all(np.diff(errors) < 0), "the error must decrease with every order"
    rho_fit, alpha = _geometric_fit(orders, errors)
    assert rho_fit == pytest.approx(rho, rel=0.03), (rho_fit, rho)
    # The algebraic prefactor of the tail is N^(-3/2) (terms c_m/(2m+1) ~ m^(-3/2)), up to the fit's slack.
    assert -3.0 < alpha < 0.0


def test_at_the_turning_point_convergence_is_only_algebraic():
    """k^2 u^2 = 1 (a body at rest, the quarter period): error ~ N^(-1/2) at every amplitude."""
    orders = [8, 16, 32, 64, 128]
    for amp_deg in (10, 90, 150):
        s = math.sin(math.radians(amp_deg) / 2)
        with mpmath.workdps(40):
            s_mp = mpmath.sin(mpmath.radians(amp_deg) / 2)
            errors = _errors(s_mp, 1 / s_mp**2, orders)
        slope = np.polyfit(np.log(orders), np.log(errors), 1)[0]
        assert slope == pytest.approx(-0.5, abs=0.12), (amp_deg, slope)
        assert errors[-1] > 0.02  # even order 128 is off by percents: no geometric convergence
        assert s > 0


def test_printed_and_corrected_differ_by_the_misprinted_term():
    """(54) as printed has 1*3/(2*4*6) k^4 u^5 instead of 1*3/(2*4*5): difference -k^4 u^5 / 80."""
    with mpmath.workdps(50):
        for u, k2 in (("0.3", "2.5"), ("0.7", "0.4"), ("-0.2", "11"), ("0.9", "1.2")):
            u, k2 = mpmath.mpf(u), mpmath.mpf(k2)
            diff = paper_series_as_printed(u, k2) - paper_series_corrected(u, k2)
            assert abs(diff + k2**2 * u**5 / 80) < mpmath.mpf(10) ** -45
            assert abs(series_integral("printed", u, k2) - paper_series_as_printed(u, k2)) < mpmath.mpf(10) ** -45
            assert abs(series_integral("corrected", u, k2) - paper_series_corrected(u, k2)) < mpmath.mpf(10) ** -45


def test_corrected_beats_printed_everywhere_and_by_orders_of_magnitude_near_the_bottom():
    for regime in (LIBRATION, ROTATION):
        printed, corrected, order2 = series_error_maps(("printed", "corrected", 2), regime, n_parameter=12, n_fraction=12)
        assert np.all(corrected.rel_error < printed.rel_error)
        # The 3x3 block holds all of order 2 plus some (positive) higher terms.
        assert np.all(corrected.rel_error <= order2.rel_error)
        if regime == LIBRATION:
            # Near the bottom of a swing the printed error is the misprint, (k^2 u^2)^2/80 relative;
            # the corrected one is O(u^6 (1 + k^6)): at phi = phi_max/12 five to 40 times smaller.
            assert np.all(printed.rel_error[:, 0] > 5 * corrected.rel_error[:, 0])
        else:
            # Over the top the misprint carries k^4 < 1: it matters less at high energy (small k^2).
            gain = printed.rel_error[:, 0] / corrected.rel_error[:, 0]
            assert np.all(np.diff(gain) > 0)  # the gain grows with k^2


def test_error_map_shape_and_monotone_along_the_arc():
    m = series_error_map(8, LIBRATION, n_parameter=10, n_fraction=15)
    assert m.rel_error.shape == (10, 15) == m.ratio.shape
    assert np.all(np.diff(m.rel_error, axis=1) > 0)  # worse towards the turning point
    assert np.allclose(m.ratio[:, -1], 1.0)  # the turning point: k^2 u^2 = 1
    assert np.all(m.k2 > 1)
    r = series_error_map("corrected", ROTATION, n_parameter=6, n_fraction=5)
    assert np.all(r.k2 < 1) and np.allclose(r.ratio[:, -1], 1.0)  # the top: u = 1
    with pytest.raises(ValueError):
        series_error_map("bogus")
    with pytest.raises(ValueError):
        series_error_map(4, ROTATION, parameter=[1.5])


def test_amplitude_table():
    table = series_error_table(amplitudes_deg=(10, 90, 170), kinds=("printed", "corrected", 8, 16), fractions=(0.5, 1.0))
    for amp in (10, 90, 170):
        assert table.error(16, amp, 0.5) < table.error(8, amp, 0.5) < table.error("corrected", amp, 0.5)
        assert table.error("corrected", amp, 0.5) < table.error("printed", amp, 0.5)
        assert table.error(16, amp, 1.0) > 0.05  # the quarter period is never right to better than 5 %
    assert table.error(8, 10, 0.5) < 1e-6
    text = table.to_markdown()
    assert "turning point" in text and "order 16" in text


def test_series_error_figure(tmp_path):
    maps = series_error_maps(("printed", "corrected", 8), n_parameter=8, n_fraction=8)
    path = series_error_figure(maps, tmp_path / "series.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in tmp_path.iterdir()] == ["series.png"]


# ----------------------------------------------------------------------------- the paper's method


@pytest.fixture(scope="module")
def scenes():
    return {"default": heyroll.default_scene(), "disk_and_ring": heyroll.load_scene(EXAMPLE)}


@pytest.mark.parametrize("name", ["default", "disk_and_ring"])
def test_paper_method_with_exact_F_reproduces_the_reference(scenes, name):
    r = paper_method_first_collision(scenes[name], "exact")
    assert r.ok, r.message
    assert r.t_rel_error < 1e-25 and r.phi_abs_error < 1e-25


@pytest.mark.parametrize("name", ["default", "disk_and_ring"])
def test_paper_method_error_shrinks_with_order(scenes, name):
    results = {kind: paper_method_first_collision(scenes[name], kind) for kind in ("printed", "corrected", 4, 8, 16, 32)}
    assert all(r.ok and r.monotone for r in results.values()), [r.message for r in results.values()]
    t_err = [results[n].t_rel_error for n in (4, 8, 16, 32)]
    assert all(a > b for a, b in zip(t_err, t_err[1:])), t_err
    # The rolling law's series is the paper's own 3x3 block: the corrected one is the better.
    assert results["corrected"].t_rel_error < results["printed"].t_rel_error
    assert results[32].t_rel_error < 0.5 * results["corrected"].t_rel_error
    first = results[8]
    assert first.t_exact > 0 and math.isfinite(first.t_series) and len(first.ratio) == 2


def test_paper_method_is_accurate_where_the_series_converge():
    """Both balls moving fast and colliding near the bottom: rho well below 1, geometric convergence."""
    scene = heyroll.parse_scene(
        """
[track]
type = "circle"
radius = 1.0
[[bodies]]
shape = "solid_sphere"
radius = 0.1
mass = 1.0
phi = -0.6
dphi = 4.0
[[bodies]]
shape = "solid_sphere"
radius = 0.15
mass = 3.0
phi = 0.6
dphi = -4.0
"""
    )
    errs = {kind: paper_method_first_collision(scene, kind) for kind in ("printed", "corrected", 8, 16)}
    assert all(r.ok for r in errs.values())
    assert max(errs[8].ratio) < 0.2
    assert errs["corrected"].t_rel_error < 1e-3
    assert errs[16].t_rel_error < 1e-12 < errs[8].t_rel_error < errs["corrected"].t_rel_error < errs["printed"].t_rel_error


def test_paper_method_reports_a_body_that_turns_back():
    """Ball 2 first rises away from ball 1, turns, and is hit on the way down: not a monotone arc."""
    scene = heyroll.parse_scene(
        """
[track]
type = "circle"
radius = 1.0
[[bodies]]
shape = "solid_sphere"
radius = 0.1
density = 7850.0
phi = -1.4
dphi = 0.6
[[bodies]]
shape = "solid_sphere"
radius = 0.15
density = 7850.0
phi = 0.7
dphi = 0.5
"""
    )
    r = paper_method_first_collision(scene, "corrected")
    assert r.status == "not_monotone" and r.monotone is False
    assert "body 2" in r.message and "monotone" in r.message
    assert math.isnan(r.t_series) and math.isnan(r.phi_series)
    assert r.t_exact > 0


def test_paper_method_unsupported_scenes():
    single = heyroll.parse_scene(
        '[track]\ntype = "circle"\nradius = 1.0\n[[bodies]]\nshape = "disk"\nradius = 0.1\nmass = 1.0\nphi = 0.3\ndphi = 0.0\n'
    )
    r = paper_method_first_collision(single, 8)
    assert r.status == "unsupported" and not r.ok
