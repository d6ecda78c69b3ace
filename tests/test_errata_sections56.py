"""One test per entry G1-G5 of papers/ERRATA.md (sections 5-6): printed form wrong, corrected form right.

The independent fact in each is a heyoka integration of the Lagrangian
equation of motion (heyroll.simulation.path_driver) or the tangent
continuity of the track.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

from heyroll.analysis.equilibria import EquilibriumProblem, find_equilibria
from heyroll.errors import SceneError
from heyroll.model.bodies import Body
from heyroll.model.scene import Scene
from heyroll.model.frame import Frame
from heyroll.model.tracks import ArcChainTrack, CurveTrack, Segment, ThreeArcTrack
from heyroll.model.scene import RunSettings
from heyroll.simulation.driver import simulate

G = 9.81
R, R0, BETA = 1.0, 0.5, 0.2


def hump_state(omega="0", v0="-0.4", t_end="0.2"):
    """A disk on the convex arc of the three-arc track: (psi0, psi0', psi, psi') after t_end."""
    track = ThreeArcTrack.make(R, R0, BETA)
    disk = Body.of_shape("disk", "0.05", mass=1)
    piece = track.pieces(disk)[1]
    rho = R0 + 0.05
    psi0 = 0.3  # psi from the top, clockwise (s grows with psi)
    s0 = piece.s0 + rho * (psi0 + (math.pi / 2 - BETA))
    scene = Scene.make(track, [disk], [s0], [v0], frame=Frame.make(omega, 0), run=RunSettings.make(t_end))
    result = simulate(scene)
    assert result.junctions == [] and result.limiter_impacts == []
    s, v = float(result.final_state[0]), float(result.final_state[1])
    psi = (s - piece.s0) / rho - (math.pi / 2 - BETA)
    return psi0, float(v0) / rho, psi, v / rho, disk


def test_G1_convex_arc_radius_is_R0_plus_r():
    psi0, w0, psi, w, disk = hump_state()
    kappa, r = 1.5, 0.05
    def rate2(radius):  # (89): psi'^2 = psi0'^2 - 2g/(kappa radius)(cos psi - cos psi0)
        return w0**2 - 2 * G / (kappa * radius) * (math.cos(psi) - math.cos(psi0))
    assert abs(rate2(R0 + r) - w**2) < 1e-12
    assert abs(rate2(R + r) - w**2) > 1e-3  # as printed in (89)


def test_G2_third_arc_runs_from_the_junction_to_the_top():
    half = mpmath.pi / 2 - mpmath.mpf(BETA)
    first = Segment("arc", mpmath.mpf(R), "concave", -mpmath.pi, half)
    hump = Segment("arc", mpmath.mpf(R0), "convex", -half, half)
    printed = Segment("arc", mpmath.mpf(R), "concave", -mpmath.pi, half)  # (87)/(90): -pi <= phi_3 <= pi/2 - beta
    corrected = Segment("arc", mpmath.mpf(R), "concave", -half, mpmath.pi)
    with pytest.raises(SceneError, match="tangent does not match"):
        ArcChainTrack.make([first, hump, printed])
    track = ArcChainTrack.make([first, hump, corrected])
    assert float(track.segments[2].end - track.segments[2].start) == pytest.approx(float(3 * mpmath.pi / 2 - mpmath.mpf(BETA)))


def paper_characteristic_roots(track: CurveTrack, r: float, kappa: float, omega: float):
    """Roots of (97) as printed: f'(1 - r k) - 2 kappa/(3 g) Omega^2 x_C (1 - r k)."""
    xs = np.linspace(float(track.x_min), float(track.x_max), 40001)
    def h(x):
        d1 = track.numeric(track.df, x)
        return G * d1 - 2 * kappa / 3 * omega**2 * (x - r * d1 / np.sqrt(1 + d1 * d1))
    v = h(xs)
    roots = []
    for k in np.flatnonzero(v[:-1] * v[1:] < 0):
        a, b = xs[k], xs[k + 1]
        for _ in range(80):
            m = 0.5 * (a + b)
            a, b = (m, b) if h(a) * h(m) > 0 else (a, m)
        roots.append(0.5 * (a + b))
    return roots


@pytest.mark.parametrize("shape, kappa", [("disk", 1.5), ("solid_sphere", 1.4), ("ring", 2.0)])
def test_G3_characteristic_equation_has_no_factor_2kappa_over_3(shape, kappa):
    track = CurveTrack.make("0.5*x**2*(x**2 - 1)**2", -1.6, 1.6)
    body = Body.of_shape(shape, "0.05", mass=1)
    frame = Frame.make(3, 0)
    ours = [e.x for e in find_equilibria(EquilibriumProblem(track, body, frame))]
    printed = paper_characteristic_roots(track, 0.05, kappa, 3.0)

    def drift(x0):  # a body released at rest at x0: how far it moves in 0.3 s
        scene = Scene.make(track, [body], [x0], [0], frame=frame, run=RunSettings.make("0.3"))
        return abs(float(simulate(scene).final_state[0]) - x0)

    outer = max(ours)  # the outer centre, where the centrifugal term matters most
    assert drift(outer) < 1e-12
    printed_outer = max(printed)
    if shape == "disk":  # 2 kappa / 3 = 1: the paper's thin disk
        assert abs(printed_outer - outer) < 1e-12
    else:
        assert abs(printed_outer - outer) > 1e-4 and drift(printed_outer) > 1e-4


def test_G4_first_integral_eq92_has_the_square_root_over_everything():
    track = CurveTrack.make("0.5*x**2*(x**2 - 1)**2", -1.6, 1.6)
    disk = Body.of_shape("disk", "0.05", mass=1)
    r, kappa, omega = 0.05, 1.5, 3.0
    x0, v0 = 1.3, 0.4
    scene = Scene.make(track, [disk], [x0], [v0], frame=Frame.make(omega, 0), run=RunSettings.make("0.3"))
    res = simulate(scene)
    x, v = float(res.final_state[0]), float(res.final_state[1])
    F = lambda q: float(track.metric(q, r))  # noqa: E731
    xc = lambda q: float(track.centre_at(q, r)[0])  # noqa: E731
    yc = lambda q: float(track.centre_at(q, r)[1])  # noqa: E731
    # J_z = m x_C^2 + const, J_P = kappa m r^2
    rest = omega**2 * (xc(x) ** 2 - xc(x0) ** 2) / (kappa * F(x)) + 2 * G / (kappa * F(x)) * (yc(x0) - yc(x))
    corrected = math.copysign(math.sqrt(v0**2 * F(x0) / F(x) + rest), v)
    printed = math.copysign(math.sqrt(v0**2) * F(x0) / F(x) + rest, v)
    assert abs(corrected - v) < 1e-12
    assert abs(printed - v) > 1e-3


def test_G5_convex_arc_phase_trajectory_in_the_rotating_plane_has_minus_gravity():
    omega = 1.2
    psi0, w0, psi, w, disk = hump_state(omega=str(omega))
    kappa, rho = 1.5, R0 + 0.05
    lam = G / (rho * omega**2)
    centrifugal = -0.25 * (math.cos(2 * psi) - math.cos(2 * psi0))
    printed = w0**2 + 2 * omega**2 / kappa * (lam * (math.cos(psi) - math.cos(psi0)) + centrifugal)  # (101)
    corrected = w0**2 + 2 * omega**2 / kappa * (-lam * (math.cos(psi) - math.cos(psi0)) + centrifugal)
    assert abs(corrected - w**2) < 1e-12
    assert abs(printed - w**2) > 1e-3
