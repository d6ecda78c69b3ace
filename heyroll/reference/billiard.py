"""Exact impact sequence of rolling balls and particles on a billiard table, in mpmath.

An independent reference for the table engine (issue 14). It reads only the
raw inputs of a :class:`heyroll.model.table.TableScene` (the boundary's
numbers: a, b / width, height / vertices / radius; each ball's R, m, kappa,
x, y, vx, vy; the laws' names and restitutions) and derives the rest here,
by geometry rather than through the engine's gap polynomials:

* a ball rolls in a straight line at constant velocity (no friction acts on
  a rolling ball on a level table);
* a cushion impact is where the centre's distance from the cushion reaches
  R. On an ellipse that distance is found from the foot point (the nearest
  point a cos th, b sin th, by Newton's method on (c - P(th)) . P'(th) = 0),
  and along a chord R - dist is convex (the distance to the boundary of a
  convex set is concave inside it), so the first crossing is bracketed and
  polished by the secant method at the working precision. A particle in an
  ellipse, a circle and straight walls give quadratic or linear equations;
* a ball-ball impact is the smaller root of |dc + dv t| = R_i + R_j;
* the laws: the cushion's `rolling` model (v_n -> -k v_n, tangential part
  kept); Hedrih's law on omega_n = v_n / R with J_P = kappa m R^2 (eqs. 8-11),
  Newton's on v_n with m, and the paper's literal `mirror` (each ball's v_n ->
  -k v_n), all along the line of centres.

Only rolling motion (no `slide` model, no initial slip) and one impact at a
time are covered; sliding and simultaneous impacts are checked against
closed forms in the tests. Two contact modes have their own references: a
ball rolling along an elliptical cushion (:func:`reference_ride`) and a
ball skidding along a circular one (:func:`reference_skid`).
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath


@dataclass(frozen=True)
class ReferenceImpact:
    t: mpmath.mpf
    i: int  # 1-based
    j: int  # 0: the cushion
    state_after: tuple  # per ball (x, y, vx, vy)


def reference_impacts(scene, n_impacts: int, dps: int = 50) -> list[ReferenceImpact]:
    """The first ``n_impacts`` impacts of ``scene`` computed at ``dps`` digits."""
    if scene.slides:
        raise ValueError("the billiard reference covers rolling motion only (no slide model, no initial slip)")
    with mpmath.workdps(dps):
        balls = [[mpmath.mpf(b.x), mpmath.mpf(b.y), mpmath.mpf(b.vx), mpmath.mpf(b.vy)] for b in scene.balls]
        radii = [mpmath.mpf(b.body.radius) for b in scene.balls]
        t = mpmath.mpf(0)
        out = []
        eps = mpmath.mpf(10) ** (-dps + 10)
        last = None
        while len(out) < n_impacts:
            best = None
            for k, ball in enumerate(balls):
                hit = _cushion_time(scene.boundary, ball, radii[k], eps if last == ("wall", k) else 0)
                if hit is not None and (best is None or hit[0] < best[0]):
                    best = (hit[0], ("wall", k), hit[1])
            for i in range(len(balls)):
                for j in range(i + 1, len(balls)):
                    tau = _pair_time(balls[i], balls[j], radii[i] + radii[j])
                    if tau is not None and (best is None or tau < best[0]):
                        best = (tau, ("pair", i, j), None)
            if best is None:
                break
            tau, what, normal = best
            for ball in balls:
                ball[0] += ball[2] * tau
                ball[1] += ball[3] * tau
            t += tau
            if what[0] == "wall":
                k = what[1]
                _reflect(balls[k], normal, mpmath.mpf(scene.cushion.restitution))
                out.append(ReferenceImpact(t, k + 1, 0, tuple(tuple(b) for b in balls)))
            else:
                i, j = what[1], what[2]
                _collide(scene, balls, radii, i, j)
                out.append(ReferenceImpact(t, i + 1, j + 1, tuple(tuple(b) for b in balls)))
            last = what
        return out


def _reflect(ball, normal, k):
    vn = ball[2] * normal[0] + ball[3] * normal[1]
    ball[2] -= (1 + k) * vn * normal[0]
    ball[3] -= (1 + k) * vn * normal[1]


def _collide(scene, balls, radii, i, j):
    bi, bj = balls[i], balls[j]
    dx, dy = bj[0] - bi[0], bj[1] - bi[1]
    d = mpmath.sqrt(dx * dx + dy * dy)
    n = (dx / d, dy / d)
    vi = bi[2] * n[0] + bi[3] * n[1]
    vj = bj[2] * n[0] + bj[3] * n[1]
    k = mpmath.mpf(scene.law.restitution)
    body_i, body_j = scene.balls[i].body, scene.balls[j].body
    name = scene.law.name
    if name == "mirror":
        new_i, new_j = -k * vi, -k * vj
    else:
        if name == "hedrih":  # on omega_n = v_n / R with J_P = kappa m R^2 (eqs. 8-11)
            ci, cj = 1 / radii[i], 1 / radii[j]
            mi = mpmath.mpf(body_i.kappa) * mpmath.mpf(body_i.mass) * radii[i] ** 2
            mj = mpmath.mpf(body_j.kappa) * mpmath.mpf(body_j.mass) * radii[j] ** 2
        else:  # newton: on v_n with the masses (eqs. 1-5)
            ci = cj = mpmath.mpf(1)
            mi, mj = mpmath.mpf(body_i.mass), mpmath.mpf(body_j.mass)
        ui, uj = ci * vi, cj * vj
        ui_new = ui - (1 + k) * mj / (mi + mj) * (ui - uj)
        uj_new = uj + (1 + k) * mi / (mi + mj) * (ui - uj)
        new_i, new_j = ui_new / ci, uj_new / cj
    for ball, old, new in ((bi, vi, new_i), (bj, vj, new_j)):
        ball[2] += (new - old) * n[0]
        ball[3] += (new - old) * n[1]


def _pair_time(a, b, reach):
    dx, dy = b[0] - a[0], b[1] - a[1]
    ux, uy = b[2] - a[2], b[3] - a[3]
    qa = ux * ux + uy * uy
    qb = 2 * (dx * ux + dy * uy)
    qc = dx * dx + dy * dy - reach * reach
    if qb >= 0 or qa == 0:
        return None
    disc = qb * qb - 4 * qa * qc
    if disc < 0:
        return None
    tau = (-qb - mpmath.sqrt(disc)) / (2 * qa)
    return tau if tau > 0 else None


def _cushion_time(boundary, ball, radius, skip):
    """(time to the first cushion contact, outward unit normal there), or None."""
    x, y, vx, vy = ball
    if vx == 0 and vy == 0:
        return None
    kind = boundary.kind
    if kind == "circle":
        rho = mpmath.mpf(boundary.radius) - radius
        qa, qb, qc = vx * vx + vy * vy, 2 * (x * vx + y * vy), x * x + y * y - rho * rho
        tau = (-qb + mpmath.sqrt(qb * qb - 4 * qa * qc)) / (2 * qa)
        px, py = x + vx * tau, y + vy * tau
        return tau, (px / rho, py / rho)
    if kind in ("rectangle", "polygon"):
        verts = [(mpmath.mpf(p), mpmath.mpf(q)) for p, q in boundary.vertices]
        area = sum(verts[m][0] * verts[(m + 1) % len(verts)][1] - verts[(m + 1) % len(verts)][0] * verts[m][1]
                   for m in range(len(verts)))
        if area < 0:
            verts = verts[::-1]
        best = None
        for m in range(len(verts)):
            (x0, y0), (x1, y1) = verts[m], verts[(m + 1) % len(verts)]
            length = mpmath.sqrt((x1 - x0) ** 2 + (y1 - y0) ** 2)
            nx, ny = (y1 - y0) / length, -(x1 - x0) / length
            rate = vx * nx + vy * ny
            if rate <= 0:
                continue
            tau = (nx * (x0 - x) + ny * (y0 - y) - radius) / rate
            if tau > skip and (best is None or tau < best[0]):
                best = (tau, (nx, ny))
        return best
    a, b = mpmath.mpf(boundary.a), mpmath.mpf(boundary.b)
    if radius == 0:
        qa = vx * vx / a**2 + vy * vy / b**2
        qb = 2 * (x * vx / a**2 + y * vy / b**2)
        qc = x * x / a**2 + y * y / b**2 - 1
        tau = (-qb + mpmath.sqrt(qb * qb - 4 * qa * qc)) / (2 * qa)
        px, py = x + vx * tau, y + vy * tau
        gx, gy = px / a**2, py / b**2
        g = mpmath.sqrt(gx * gx + gy * gy)
        return tau, (gx / g, gy / g)

    def excess(tau):  # R - distance from the ellipse: convex along the chord
        return radius - _ellipse_distance(a, b, x + vx * tau, y + vy * tau)[0]

    # bracket: the centre's line leaves the ellipse itself (a quadratic) where the excess is R > 0;
    # before that the excess is convex, negative now, so it crosses 0 once on the way
    qa = vx * vx / a**2 + vy * vy / b**2
    qb = 2 * (x * vx / a**2 + y * vy / b**2)
    qc = x * x / a**2 + y * y / b**2 - 1
    hi = (-qb + mpmath.sqrt(qb * qb - 4 * qa * qc)) / (2 * qa)
    lo = mpmath.mpf(0) if skip == 0 else skip
    for _ in range(40):
        mid = (lo + hi) / 2
        if excess(mid) < 0:
            lo = mid
        else:
            hi = mid
    tau = mpmath.findroot(excess, (lo, hi), solver="secant")
    px, py = x + vx * tau, y + vy * tau
    _, (fx, fy) = _ellipse_distance(a, b, px, py)
    d = mpmath.sqrt((fx - px) ** 2 + (fy - py) ** 2)
    return tau, ((fx - px) / d, (fy - py) / d)


def _ellipse_distance(a, b, px, py):
    """(distance, foot point) of an inside point from the ellipse (nearest point, by Newton on the angle)."""
    # start from the angle of the point scaled onto the ellipse's normal direction: near the
    # boundary the nearest point's eccentric angle is close to atan2(a py, b px)
    th = mpmath.atan2(a * py, b * px)
    for _ in range(200):
        c, s = mpmath.cos(th), mpmath.sin(th)
        f = (a * c - px) * (-a * s) + (b * s - py) * (b * c)  # (P - p) . P'
        df = (a * s) ** 2 + (b * c) ** 2 + (a * c - px) * (-a * c) + (b * s - py) * (-b * s)
        step = f / df
        th -= step
        if abs(step) < mpmath.eps * 4:
            break
    fx, fy = a * mpmath.cos(th), b * mpmath.sin(th)
    return mpmath.sqrt((fx - px) ** 2 + (fy - py) ** 2), (fx, fy)


def reference_ride(a, b, radius, x0, y0, vx, vy, duration, dps: int = 40) -> tuple:
    """(x, y) of a ball of radius R riding an elliptical cushion (a = b: a circle) for ``duration`` s.

    The engine's ride (heyroll.simulation.table.system): the centre moves along the inner parallel curve
    C(th) = P(th) - R n(th) at the constant speed |v|, in the direction of v. Here by arc length:
    |C'(th)| = |P'(th)| (1 - R kappa(th)) = |P'| - R a b / |P'|^2 (kappa = a b / |P'|^3 the ellipse's
    curvature), s(th) by Gauss-Legendre quadrature, the foot angle th0 of the start by Newton's method on
    (c0 - C(th)) . C'(th) = 0, the end th1 by Newton's method on s(th1) - s(th0) = +-|v| duration.
    """
    with mpmath.workdps(dps):
        a, b, r = mpmath.mpf(a), mpmath.mpf(b), mpmath.mpf(radius)
        x0, y0, vx, vy = (mpmath.mpf(v) for v in (x0, y0, vx, vy))

        def speed(th):  # |P'(th)|
            return mpmath.sqrt((a * mpmath.sin(th)) ** 2 + (b * mpmath.cos(th)) ** 2)

        def curve(th):
            m = speed(th)
            return (a * mpmath.cos(th) - r * b * mpmath.cos(th) / m, b * mpmath.sin(th) - r * a * mpmath.sin(th) / m)

        def tangent(th):
            return mpmath.diff(lambda t: curve(t)[0], th), mpmath.diff(lambda t: curve(t)[1], th)

        def foot(th):
            cx, cy = curve(th)
            tx, ty = tangent(th)
            return (x0 - cx) * tx + (y0 - cy) * ty

        th0 = mpmath.findroot(foot, mpmath.atan2(y0 / b, x0 / a))
        tx, ty = tangent(th0)
        sign = 1 if tx * vx + ty * vy >= 0 else -1
        target = mpmath.sqrt(vx * vx + vy * vy) * mpmath.mpf(duration)

        def element(th):
            m = speed(th)
            return m - r * a * b / m**2

        perimeter = mpmath.quad(element, [0, mpmath.pi / 2, mpmath.pi, 3 * mpmath.pi / 2, 2 * mpmath.pi])
        laps = mpmath.floor(target / perimeter)
        rest = target - laps * perimeter
        guess = th0 + sign * 2 * mpmath.pi * rest / perimeter
        th1 = mpmath.findroot(lambda th: sign * mpmath.quad(element, [th0, th]) - rest, guess)
        return curve(th1)


def reference_skid(rho, kappa, mu_g, x0, y0, vx, vy, ux, uy, duration, dps: int = 30) -> tuple:
    """(x, y, vx, vy, ux, uy, nu) of a ball skidding along a circular cushion (its centre on the circle of
    radius ``rho`` about the origin) after ``duration`` s; nu, the cushion's push per unit mass, < 0 where the
    ball would have lifted off before (the skid's slip must not reach 0 within ``duration``).

    Independent of the engine's constraint form (heyroll.simulation.table.system: -lambda grad g with the
    gap's Hessian): here in polar form, the angle th of the centre, its tangential speed V, the slip's
    tangential and outward components u_t, u_n in the frame turning with the centre:

        V' = f_t,  nu = f_n + V^2/rho (the cushion's push inward, per unit mass),
        u_t' = kappa/(kappa - 1) f_t - u_n V/rho,  u_n' = kappa/(kappa - 1) f_n - nu + u_t V/rho,
        th' = V/rho,  f = -mu g (u_t, u_n)/|u|,

    (the cushion's force goes through the centre: it turns v, not the spin; v' = f - nu n, w' = -f/(kappa - 1)
    with w = v - u), integrated by mpmath's Taylor-series ODE solver at ``dps`` digits.
    """
    with mpmath.workdps(dps):
        rho, kappa, mu_g = (mpmath.mpf(v) for v in (rho, kappa, mu_g))
        x0, y0, vx, vy, ux, uy, duration = (mpmath.mpf(v) for v in (x0, y0, vx, vy, ux, uy, duration))
        th0 = mpmath.atan2(y0, x0)
        tx, ty, nx, ny = _circle_frame(th0)
        ratio = kappa / (kappa - 1)

        def rates(t, z):
            th, v, ut, un = z
            slip = mpmath.sqrt(ut * ut + un * un)
            ft, fn = -mu_g * ut / slip, -mu_g * un / slip
            nu = fn + v * v / rho
            return [v / rho, ft, ratio * ft - un * v / rho, ratio * fn - nu + ut * v / rho]

        solution = mpmath.odefun(rates, 0, [th0, vx * tx + vy * ty, ux * tx + uy * ty, ux * nx + uy * ny])
        th, v, ut, un = solution(duration)
        nu = -mu_g * un / mpmath.sqrt(ut * ut + un * un) + v * v / rho
        tx, ty, nx, ny = _circle_frame(th)
        return (rho * nx, rho * ny, v * tx, v * ty, ut * tx + un * nx, ut * ty + un * ny, nu)


def reference_skid_end(rho, kappa, mu_g, x0, y0, vx, vy, ux, uy, slip_end, dps: int = 30) -> tuple:
    """(t, x, y, vx, vy, ux, uy) where the slip of a ball skidding along a circular cushion (as in
    :func:`reference_skid`) has fallen to ``slip_end``; for a slip that only falls (no inward component at
    the start: |u|' = -kappa/(kappa - 1) mu g - nu sin(phi) < 0 with nu >= 0, phi its angle from the tangent).

    In time the slip's direction has a branch point where |u| reaches 0 (phi' = V/rho - nu cos(phi)/|u|);
    here the independent variable is sigma = -log |u| (increasing, as mpmath's solver needs), in which the
    motion is regular down to |u| = 0:

        d(t, th, V, phi)/d sigma = -|u|/|u|' (1, V/rho, f_t, V/rho - nu cos(phi)/|u|),

    integrated from -log |u0| to -log ``slip_end`` by mpmath's Taylor-series ODE solver at ``dps`` digits."""
    with mpmath.workdps(dps):
        rho, kappa, mu_g, slip_end = (mpmath.mpf(v) for v in (rho, kappa, mu_g, slip_end))
        x0, y0, vx, vy, ux, uy = (mpmath.mpf(v) for v in (x0, y0, vx, vy, ux, uy))
        th0 = mpmath.atan2(y0, x0)
        tx, ty, nx, ny = _circle_frame(th0)
        ratio = kappa / (kappa - 1)

        def rates(sigma, z):
            t, th, v, phi = z
            slip = mpmath.exp(-sigma)
            c, s = mpmath.cos(phi), mpmath.sin(phi)
            nu = -mu_g * s + v * v / rho
            falling = -ratio * mu_g - nu * s
            scale = -slip / falling
            return [scale, scale * v / rho, -scale * mu_g * c, scale * v / rho + nu * c / falling]

        u_t, u_n = ux * tx + uy * ty, ux * nx + uy * ny
        start = -mpmath.log(mpmath.sqrt(u_t * u_t + u_n * u_n))
        solution = mpmath.odefun(rates, start, [mpmath.mpf(0), th0, vx * tx + vy * ty, mpmath.atan2(u_n, u_t)])
        t, th, v, phi = solution(-mpmath.log(slip_end))
        tx, ty, nx, ny = _circle_frame(th)
        ut, un = slip_end * mpmath.cos(phi), slip_end * mpmath.sin(phi)
        return (t, rho * nx, rho * ny, v * tx, v * ty, ut * tx + un * nx, ut * ty + un * ny)


def _circle_frame(th) -> tuple:
    """(t_x, t_y, n_x, n_y) at angle ``th`` on a circle about the origin: the counter-clockwise tangent and the
    outward normal (reference_skid, reference_skid_end)."""
    return -mpmath.sin(th), mpmath.cos(th), mpmath.cos(th), mpmath.sin(th)
