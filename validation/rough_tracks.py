"""Rough tracks (Coulomb friction): accuracy of the transition instants, energy per branch, cost per event.

    python validation/rough_tracks.py [--quick] [--t-end 2000] [--output validation/reports/rough_tracks.md]

(a) Transition instants against closed forms evaluated with mpmath at 40
    digits (heyroll.reference.rough, independent of the engine), from the
    engine's own double inputs (a decimal start is the double the engine sees):

    * a particle launched uphill on the straight rough incline y = 0.5 x:
      stopping time v0 / (g (sin a + mu cos a)) and place;
    * a particle inside the rough circle R = 1 m: every turning point and its
      instant (phi'^2 = y(phi) in closed form on each branch, roots by mpmath),
      up to the final sticking, from two starts;
    * a rolling disk launched with a slip w0 on the flat y = 0: the instant it
      rolls again, t* = |w0| / (g mu kappa/(kappa - 1)); and on the rough incline
      y = 0.3 x (heyroll.reference.rough.incline_slip_then_roll).

(b) Energy per branch for the circle particle: the drop of its mechanical energy
    E_i - E_{i+1} between consecutive changes of mode against the friction work the
    run records over it (transition_work differences) and against the closed-form
    work; max relative error (to the branch's drop).

(c) Cost per event: a forced stick-slip run (particle on y = x^2/2, x in [-2, 2],
    mu = 0.1, mu_s = 0.2, force of amplitude 2 and frequency 2, t_end = --t-end),
    wall time of the first run (compilation included) and of a second identical
    run (compiled: the cost), per change of mode.

Prints a markdown report and writes it to --output (validation/reports/rough_tracks.md).
--quick: a shorter forced run (t_end 100 s) and only the first circle start.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import heyoka as hy
import mpmath
import numpy as np

from heyroll.interfaces.outputs import versions
from heyroll.model.bodies import Body
from heyroll.model.forcing import Forcing
from heyroll.model.scene import RunSettings, Scene
from heyroll.model.tracks import CircleTrack, CurveTrack, first_integral
from heyroll.reference import rough
from heyroll.simulation.driver import simulate
from _report import publish

REPORT = Path(__file__).parent / "reports" / "rough_tracks.md"
DPS = 40
MU, MU_S = 0.1, 0.2


def particle() -> Body:
    return Body.of_shape("particle", 0, mass=1.0)


def mp(x):
    """The exact value of a double (or of a decimal string) as an mpf at the working precision."""
    return mpmath.mpf(x)


def row(case, quantity, engine, reference) -> dict:
    with mpmath.workdps(DPS):
        err = abs(mp(engine) - reference)
    return dict(case=case, quantity=quantity, engine=float(engine), reference=mpmath.nstr(reference, 20),
                error=float(err))


# -- (a) transition instants ---------------------------------------------------------------------


def incline_rows() -> list[dict]:
    slope, dx0 = 0.5, 3.0
    scene = Scene.make(CurveTrack.make(f"{slope}*x", -20, 20), [particle()], [0.0], [dx0], friction=MU,
                       static_friction=MU_S, track_sides="one", limiter_restitution=0.5, run=RunSettings.make(2.0))
    result = simulate(scene)
    g = float(scene.g)
    turn = next(tr for tr in result.transitions if tr[2] == "sliding+")
    with mpmath.workdps(DPS + 10):
        alpha = mpmath.atan(mp(slope))
        v0 = mp(dx0) * mpmath.sqrt(1 + mp(slope) ** 2)  # speed along the slope
        t_stop = rough.incline_stopping_time(alpha, MU, v0, g, dps=DPS)
        x_stop = rough.incline_stopping_distance(alpha, MU, v0, g, dps=DPS) * mpmath.cos(alpha)
    case = f"particle on y = {slope} x, x' = {dx0} (-> {turn[3]})"
    return [row(case, "stopping time t (s)", turn[0], t_stop), row(case, "stopping place x (m)", float(turn[4]), x_stop)]


def circle_run(phi0, dphi0, t_end=10.0):
    scene = Scene.make(CircleTrack.of_radius(1), [particle()], [phi0], [dphi0], friction=MU, static_friction=MU_S,
                       run=RunSettings.make(t_end))
    result = simulate(scene)
    ref = rough.circle_sliding_sequence(phi0, dphi0, MU, MU_S, 1, float(scene.g), dps=DPS)
    return result, ref


def circle_rows(starts) -> tuple[list[dict], list[dict]]:
    rows, balance = [], []
    for phi0, dphi0 in starts:
        result, ref = circle_run(phi0, dphi0)
        engine = [tr for tr in result.transitions if tr[0] > 0]  # a restart at t = 0 is the reference's mode0
        case = f"particle in circle R = 1, phi0 = {phi0}, phi0' = {dphi0}"
        if [(tr[2], tr[3]) for tr in engine] != [(x.mode_from, x.mode_to) for x in ref.transitions]:
            raise SystemExit(f"{case}: modes {[(tr[2], tr[3]) for tr in engine]} differ from the closed form's "
                             f"{[(x.mode_from, x.mode_to) for x in ref.transitions]}")
        for n, (tr, x) in enumerate(zip(engine, ref.transitions), start=1):
            rows.append(row(case, f"transition {n} ({x.mode_from} -> {x.mode_to}) t (s)", tr[0], x.t))
            rows.append(row(case, f"transition {n} phi (rad)", float(tr[4]), x.phi))
        balance.append(branch_balance(result, ref, case))
    return rows, balance


def slip_rows() -> list[dict]:
    disk = Body.of_shape("disk", 0.1, mass=1.0)
    kappa = mpmath.mpf(3) / 2
    out = []
    for slope, dx0, w0 in ((0.0, 1.0, 0.5), (0.3, 1.5, 0.4)):
        y = "0*x" if slope == 0 else f"{slope}*x"
        scene = Scene.make(CurveTrack.make(y, -20, 20), [disk], [0.0], [dx0], friction=MU, static_friction=MU_S,
                           track_sides="one", limiter_restitution=0.5, slip=[w0], run=RunSettings.make(1.0))
        result = simulate(scene)
        g = float(scene.g)
        roll = next(tr for tr in result.transitions if tr[3] == "rolling")
        with mpmath.workdps(DPS + 10):
            if slope == 0:
                t_star = abs(mp(w0)) / (g * MU * kappa / (kappa - 1))
                what = "t* = abs(w0) / (g mu kappa/(kappa - 1))"
            else:
                alpha = mpmath.atan(mp(slope))
                v0 = mp(dx0) * mpmath.sqrt(1 + mp(slope) ** 2)
                ref = rough.incline_slip_then_roll(alpha, MU, MU_S, kappa, v0, v0 - mp(w0), g, dps=DPS)
                t_star = ref.t_star
                what = f"t* (incline_slip_then_roll; then {ref.mode_after})"
        case = f"disk r = 0.1 on y = {y}, x' = {dx0}, slip w0 = {w0} ({roll[2]} -> rolling)"
        out.append(row(case, what, roll[0], t_star))
    return out


# -- (b) energy per branch -----------------------------------------------------------------------


def branch_balance(result, ref, case) -> dict:
    """Per branch between consecutive changes of mode of the circle particle: drop of E vs the run's
    friction work and vs the closed-form work (relative to the drop)."""
    scene = result.scene
    body = scene.bodies[0]

    def energy(q, dq):
        return float(first_integral(scene.track, body, float(q), float(dq), scene.g, scene.frame))

    points = [(tr[4], tr[5], w) for tr, w in zip(result.transitions, result.transition_work)]
    if not result.transitions or result.transitions[0][0] > 0:  # a start with no change of mode at t = 0
        points.insert(0, (result.initial_state[0], result.initial_state[1], 0.0))
    worst_run, worst_ref, n = 0.0, 0.0, 0
    sliding = [b for b in ref.branches]
    for (q0, dq0, w0), (q1, dq1, w1), b in zip(points, points[1:], sliding):
        drop = energy(q0, dq0) - energy(q1, dq1)
        worst_run = max(worst_run, abs(drop - (w1 - w0)) / abs(drop))
        worst_ref = max(worst_ref, abs(drop + float(b.friction_work)) / abs(drop))
        n += 1
    return dict(case=case, branches=n, run=worst_run, closed_form=worst_ref)


# -- (c) cost per event --------------------------------------------------------------------------


def forced_scene(t_end) -> Scene:
    return Scene.make(CurveTrack.make("x**2/2", -2, 2), [particle()], [0.3], [0.0], friction=MU, static_friction=MU_S,
                      track_sides="one", limiter_restitution=0.5,
                      forcing=Forcing.make("force", amplitude=2.0, frequency=2.0), run=RunSettings.make(t_end))


def cost(t_end) -> dict:
    scene = forced_scene(t_end)
    t0 = time.perf_counter()
    first = simulate(scene)
    first_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    second = simulate(scene)
    second_s = time.perf_counter() - t0
    if not second.success:
        raise SystemExit(f"forced run: {second.message}")
    if len(second.transitions) != len(first.transitions):
        raise SystemExit("forced run: a repeated run differs from the first")
    n = len(second.transitions)
    kinds = {}
    for tr in second.transitions:
        kinds[f"{tr[2]} -> {tr[3]}"] = kinds.get(f"{tr[2]} -> {tr[3]}", 0) + 1
    return dict(t_end=t_end, first_s=first_s, second_s=second_s, transitions=n, steps=second.steps,
                us=1e6 * second_s / max(n, 1), first_us=1e6 * first_s / max(n, 1), kinds=kinds,
                limiter=len(second.limiter_impacts), energy_lost=second.energy_initial - second.energy_final,
                friction=float(sum(second.friction_work)))


# -- report --------------------------------------------------------------------------------------


def report(rows, balance, c, quick) -> str:
    lines = [
        "# Rough tracks: transition instants, energy per branch, cost per event",
        "",
        f"mu = {MU}, mu_s = {MU_S}, g = 9.81 m/s^2, particles of mass 1 kg, double precision (tol = eps), heyoka's on-disk cache off; "
        f"references: heyroll.reference.rough at {DPS} digits from the engine's double inputs"
        f"{' (--quick)' if quick else ''}; one core of {os.cpu_count()}; versions {versions()}.",
        "",
        "## (a) Transition instants against the closed forms",
        "",
        "| case | quantity | engine | closed form (mpmath) | abs. error |",
        "|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(f"| {r['case']} | {r['quantity']} | {r['engine']:.17g} | {r['reference']} | {r['error']:.2e} |")
    times = [r["error"] for r in rows if r["quantity"].endswith("(s)") or r["quantity"].startswith("t*")]
    places = [r["error"] for r in rows if r["quantity"].endswith("(m)") or r["quantity"].endswith("(rad)")]
    lines += [
        "",
        f"- worst transition instant error: {max(times):.2e} s",
        f"- worst transition place error: {max(places):.2e} (m or rad)",
        "",
        "## (b) Energy per branch (particle in the circle)",
        "",
        "| case | branches | max rel. error, drop vs run's friction work | max rel. error, drop vs closed-form work |",
        "|---|---|---|---|",
    ]
    for b in balance:
        lines.append(f"| {b['case']} | {b['branches']} | {b['run']:.2e} | {b['closed_form']:.2e} |")
    lines += [
        "",
        f"- worst energy balance per branch: {max(max(b['run'], b['closed_form']) for b in balance):.2e} (relative)",
        "",
        "## (c) Cost per event: forced stick-slip",
        "",
        f"Particle on y = x^2/2, x in [-2, 2] (limiters, restitution 0.5), x0 = 0.3 m at rest, mu = {MU}, "
        f"mu_s = {MU_S}, force amplitude 2 N, frequency 2, t_end = {c['t_end']:g} s: {c['transitions']} changes of "
        f"mode ({', '.join(f'{k}: {v}' for k, v in sorted(c['kinds'].items()))}), {c['limiter']} limiter impacts, "
        f"{c['steps']} steps; energy lost {c['energy_lost']:.6g} J, friction work {c['friction']:.6g} J.",
        "",
        "| run | wall s | us per change of mode | steps per change of mode |",
        "|---|---|---|---|",
        f"| first (compilation included) | {c['first_s']:.3f} | {c['first_us']:.1f} | "
        f"{c['steps'] / max(c['transitions'], 1):.2f} |",
        f"| second (compiled) | {c['second_s']:.3f} | {c['us']:.1f} | {c['steps'] / max(c['transitions'], 1):.2f} |",
    ]
    return "\n".join(lines) + "\n"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="forced run of 100 s, one circle start")
    parser.add_argument("--t-end", type=float, default=None, help="t_end of the forced run (s; default 2000, quick 100)")
    parser.add_argument("--output", type=Path, default=REPORT, help="where the markdown report is written")
    args = parser.parse_args(argv)
    t_end = args.t_end if args.t_end is not None else (100.0 if args.quick else 2000.0)
    # As validation/many_bodies.py: compile for real (no heyoka on-disk cache) so that the first
    # forced run's wall time includes its compilation.
    hy.llvm_state.set_diskcache_enabled(False)
    starts = [(-1.0, 0.0)] if args.quick else [(-1.0, 0.0), (0.0, 4.0), (0.5, -2.5)]
    circle, balance = circle_rows(starts)
    rows = incline_rows() + circle + slip_rows()
    text = report(rows, balance, cost(t_end), args.quick)
    publish(text, args.output)


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
