"""Billiards (paper section 7): impact-time accuracy, speed, drift of the integrals, what a finite ball loses.

    python validation/billiards.py [--quick | --tiny] [--drift N] [--output validation/reports/billiards.md]

Balls rolling on a level table inside a cushion (heyroll.simulation.table),
a=2, b=1 for every ellipse; all runs in double unless said otherwise.

1. Impact-time accuracy against the independent mpmath reference
   (heyroll.reference.billiard, 40 digits; 50 for quad):

   * local: from the engine's own state right after impact n-1 (its doubles
     taken exactly), the reference predicts the flight time tau to impact n;
     the error |t_n - t_{n-1} - tau| / tau, max and median over the run, for a
     particle in the ellipse, a solid sphere R = 0.1 and R = 0.01 in the
     ellipse, R = 0.1 in a 2 x 1 rectangle, in a regular hexagon and in a
     circle of radius 1. The recorded t_n is a double of size t_n: rounding it
     alone costs up to ulp(t_n)/2 / tau (the "clock floor", it grows with t_n),
     so the error is also given in ulps of t_n, and as the error of the impact
     place P_n (engine) against P_{n-1} + v tau (reference) over the chord
     |v| tau, which has no clock in it;
   * global: the first impacts of a 2-ball scene against reference_impacts
     from the initial state: the error grows through the dynamics (each
     ball-ball collision and each reflection in a curved cushion amplifies a
     perturbation of the path);
   * the same in quad (precision="quad") for the R = 0.1 ball in the ellipse
     and the 2-ball scene.

2. Speed: impacts per second of a compiled run (first run: compilation +
   run; second run: the same run again, timed), heyoka's on-disk cache off
   and its in-memory cache cleared before each first run, for 1 particle and
   1 ball in the ellipse and 4 and 16 balls in a 2 x 1 rectangle.

3. Drift of the integrals of the particle in the ellipse over --drift impacts
   (1e6; --quick 1e5): the caustic parameter
   lambda = a^2 dy^2 + b^2 dx^2 - (x dy - y dx)^2 (d the unit outgoing
   direction; identically b^2 minus the product of the angular momenta about
   the foci), the speed and the energy; max |drift| and the drift at 1%, 10%
   and 100% of the run, the growth exponent of the RMS drift (1/2: a
   random walk of round-off, 1: a systematic drift) and the sign of its change
   over each tenth of the run; beside them the same map in a plain float64
   Python loop (quadratic formula, the same reflection), for scale.

4. A finite ball in the ellipse: which integrals are lost. R in (0, 0.05,
   0.2, 0.4) (R < b^2/a = 0.5), the launch (0.3, -0.2) with v = (1, 0.7):
   spread (max - min) of lambda over the impacts (with the table's a, b, and
   with a - R, b - R, the ellipse nearest the centre's curve), of the speed and
   of the energy; the Birkhoff map (arc length s of the contact point,
   sin of the reflection angle) of several launches per R in
   validation/reports/billiards_birkhoff_R.png.

Engine defect found while writing this study (commit 9b0f749): a run whose
cushion is a conic in the centre (a particle in an ellipse, any ball on a
circular table) misses cushion impacts when its step to t_end is long
(t_end - t >~ 5e3 s here): heyoka warns "polynomial root finding during event
detection failed" and the particle flies off the table while the run ends
'completed' (the table driver calls propagate_until(t_end) without
max_delta_t and does not check the final state for overlap). Every run here
is therefore cut into runs of at most CHUNK_T seconds, each restarted from the
state where the previous one ended (that state's doubles, exactly), and each
piece is checked to end on the table (`run_impacts`). A run that stops early
is listed in the report ("Engine stops"), and the defects met are probed
again at its end on the engine as it is then ("Probes").

5. Settling onto the cushion and riding it (k = 0.5, rolling cushion): the
   impacts before a ball settles, when, the energy its settle row takes, then
   a ride of --ride seconds (1e4; --quick 1e3) against
   heyroll.reference.billiard.reference_ride (arc length along the centre's
   curve at 40 digits, from the engine's state right after the settle): the
   end position's error, the relative change of the speed, the distance from
   the curve at the end (for the ellipse the exact distance by the foot point),
   and the ride's wall time, for a ball on the circle and a particle and two
   balls in the ellipse.

6. Skidding along the cushion (a riding ball sliding on the cloth, `slide`
   cushion, mu = 0.2): a ball started on a circular cushion along it without
   spin, against heyroll.reference.billiard.reference_skid (polar form, mpmath
   Taylor series) at times during the skid and reference_skid_end (the end of
   the slip, integrated in sigma = -log |u|) for the slip's end instant and
   state; a slip pointing off the cushion, whose ball lifts off: the
   reference's cushion push at the engine's lift-off instant. Then the loss of
   grip of a rolling rider on an ellipse (mu = 0.05): the state where the
   skid's slip ends for SKID_ONSET from 2^-18 to 2^-34 against the smallest,
   with the steps and wall time of each (the onset's cost and error).

7. Random dissipative scenes: seeded random tables (circle, ellipse,
   rectangle), 1-3 balls at up to 3 m/s, k_c in [0.3, 0.95], mu in
   [0.02, 0.3], either cushion model, the ball laws hedrih/newton/slide,
   30 s each: how many complete, how the others stop, wall times. Before the
   skid (the parent of this study's section 6) a slide-model ball that grazed
   or was pressed onto a cushion stopped the run.

--quick: 1e5 impacts of drift and fewer impacts elsewhere (< 3 min);
--tiny: a smoke test of every section (seconds, for tests).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import time
from pathlib import Path

import heyoka as hy
import mpmath
import numpy as np

from heyroll.interfaces.outputs import versions
from heyroll.interfaces.scene_file import parse_scene
from heyroll.reference.billiard import _cushion_time, _ellipse_distance, reference_impacts, reference_ride
from heyroll.simulation.driver import simulate
from heyroll.simulation.result import Status
from _report import publish

REPORT = Path(__file__).parent / "reports" / "billiards.md"
FIGURE_NAME = "billiards_birkhoff_R.png"
A, B = 2.0, 1.0
ELLIPSE = f'boundary = "ellipse"\na = {A}\nb = {B}'
RECTANGLE = 'boundary = "rectangle"\nwidth = 2.0\nheight = 1.0'
CIRCLE = 'boundary = "circle"\nradius = 1.0'
HEXAGON = "boundary = \"polygon\"\nvertices = [" + ", ".join(
    f"[{math.cos(k * math.pi / 3)!r}, {math.sin(k * math.pi / 3)!r}]" for k in range(6)) + "]"
#: Longest run handed to the engine in one call (s): see the module docstring.
CHUNK_T = 500.0
LAUNCH = ("0.3", "-0.2", "1.0", "0.7")
RADII = ("0", "0.05", "0.2", "0.4")
#: Launches of the Birkhoff maps: (x, y, direction angle): rotations (elliptic caustics) near the
#: cushion and near the separatrix (the orbits through the foci), librations about the minor axis.
MAP_LAUNCHES = ((0.0, 0.55, 0.0), (0.0, -0.58, 0.0), (0.0, -0.45, 0.1), (0.0, 0.3, 0.05), (0.0, -0.2, 0.0),
                (0.0, 0.08, 0.0), (0.0, 0.0, 0.25), (0.0, 0.0, 0.6), (0.0, 0.0, 1.1),
                (0.3, -0.2, math.atan2(0.7, 1.0)))


# -- scenes ------------------------------------------------------------------------------------


def table_scene(boundary: str, balls: list[dict], *, law="hedrih", name="billiard", cushion_k="1", cushion="rolling",
                friction="0.2", k="1", simultaneous="sequential"):
    """A table scene from TOML text: rolling cushion (elastic unless cushion_k), the ball law elastic unless k."""
    lines = ["[track]", 'type = "table"', boundary, f'cushion_model = "{cushion}"', f"cushion_restitution = {cushion_k}",
             f"friction = {friction}"]
    for ball in balls:
        lines.append("[[bodies]]")
        lines += [f'{key} = "{value}"' if key == "shape" else f"{key} = {value}" for key, value in ball.items()]
    lines += ["[collision]", f'law = "{law}"', f"restitution = {k}", f'simultaneous = "{simultaneous}"', "[run]",
              "t_end = 100"]
    return parse_scene("\n".join(lines), default_name=name)


def body(x, y, vx, vy, radius="0.1", mass="1", shape=None) -> dict:
    shape = shape or ("particle" if float(radius) == 0 else "solid_sphere")
    return {"shape": shape, "radius": radius, "mass": mass, "x": x, "y": y, "vx": vx, "vy": vy}


def one_ball(boundary: str, radius: str, launch=LAUNCH, name="billiard", cushion_k="1"):
    law = "newton" if float(radius) == 0 else "hedrih"
    return table_scene(boundary, [body(*launch, radius=radius)], law=law, name=name, cushion_k=cushion_k)


def grid_of_balls(n: int, seed: int = 0, radius: str = "0.05"):
    """n balls on a grid over the 2 x 1 rectangle, velocities uniform in [-1, 1]^2 (seeded)."""
    rng = np.random.default_rng([seed, n])
    cols = math.ceil(math.sqrt(2 * n))
    rows = math.ceil(n / cols)
    balls = []
    for k in range(n):
        x = -1 + (k % cols + 0.5) * 2 / cols
        y = -0.5 + (k // cols + 0.5) / rows
        vx, vy = (float(v) for v in rng.uniform(-1, 1, 2))
        balls.append(body(repr(x), repr(y), repr(vx), repr(vy), radius=radius, mass="0.17"))
    return table_scene(RECTANGLE, balls, name=f"{n} balls in the rectangle")


# -- chunked runs (module docstring) -----------------------------------------------------------


def restarted(scene, state):
    """``scene`` with every ball moved to ``state`` (the engine's doubles, exactly)."""
    balls = []
    for k, ball in enumerate(scene.balls):
        x, y, vx, vy, ux, uy = (mpmath.mpf(float(v)) for v in state[6 * k:6 * k + 6])
        balls.append(dataclasses.replace(ball, x=x, y=y, vx=vx, vy=vy, ux=ux, uy=uy))
    return dataclasses.replace(scene, balls=tuple(balls))


def on_table(scene, state, slack=1e-9) -> bool:
    for k, ball in enumerate(scene.balls):
        x, y = float(state[6 * k]), float(state[6 * k + 1])
        for w, consts in enumerate(scene.boundary.wall_constants(ball.body.radius)):
            if scene.boundary.gap(w, x, y, [float(c) for c in consts]) > slack:
                return False
    return True


#: Engine stops met by this study's runs: (what, message); listed in the report.
FAILURES: list = []


@dataclasses.dataclass
class Run:
    table: object
    impacts: int
    runs: int
    failure: str | None


def run_impacts(scene, n: int, *, columns=None, keep=True, chunk_t: float = CHUNK_T, what: str | None = None):
    """The first ``n`` impacts of ``scene`` in runs of at most ``chunk_t`` s (module docstring).

    Returns a Run: ``table`` the concatenated impact table (only ``columns`` if given; ``t`` made
    global), None without ``keep``; ``impacts``; ``runs`` the number of engine calls; ``failure``
    None, or why the engine stopped before ``n`` impacts (the table then holds the impacts before;
    the stop is also appended to FAILURES).
    """
    pieces, done, offset, runs, idle, failure = [], 0, 0.0, 0, 0, None
    while done < n:
        result = simulate(scene, t_end=chunk_t, max_collisions=n - done, max_events=None)
        runs += 1
        if keep and result.n_collisions:
            table = result.collision_table()
            table["t"] += offset
            pieces.append(table if columns is None else {c: table[c].copy() for c in columns})
        done += result.n_collisions
        offset += float(result.t_final)
        if result.status not in (Status.COMPLETED, Status.MAX_COLLISIONS):
            failure = f"{result.status.value}: {result.message}"
        elif not on_table(scene, result.state_final):
            failure = f"a ball left the table in a run of {chunk_t:g} s ending 'completed' (an impact was missed)"
        idle = 0 if result.n_collisions else idle + 1
        if failure is None and idle > 3:
            failure = f"no impact in {idle} runs of {chunk_t:g} s"
        if failure is not None:
            failure = f"after {done} of {n} impacts: {failure}"
            FAILURES.append((what or scene.name, failure))
            break
        scene = restarted(scene, result.state_final)
    if not keep:
        return Run(None, done, runs, failure)
    if not pieces:
        raise SystemExit(f"{what or scene.name}: no impact at all ({failure})")
    if columns is None:
        return Run(np.concatenate(pieces), done, runs, failure)
    return Run({c: np.concatenate([p[c] for p in pieces]) for c in columns}, done, runs, failure)


# -- 1. accuracy -------------------------------------------------------------------------------


def exact(value) -> mpmath.mpf:
    """A double exactly; a real128 through its 36 digits (round-trip)."""
    return mpmath.mpf(value) if isinstance(value, (float, np.floating)) else mpmath.mpf(str(value))


def ulp(value: float, bits: int) -> float:
    return 2.0 ** (math.frexp(abs(value))[1] - bits) if value else 0.0


def local_errors(scene, n: int, precision: str = "double", dps: int = 40) -> dict:
    """Each impact time predicted by the reference from the engine's state after the previous impact."""
    if precision == "double":
        got = run_impacts(scene, n, what=f"{scene.name} (accuracy)")
        table, failure = got.table, got.failure
        bits = 53
    else:  # short runs (t << CHUNK_T), in the run's own numbers
        result = simulate(scene, t_end=CHUNK_T, max_collisions=n, precision=precision, max_events=None)
        failure = None
        if result.status is not Status.MAX_COLLISIONS or not on_table(scene, result.state_final):
            failure = f"after {result.n_collisions} of {n} impacts: {result.status.value}: {result.message}"
            FAILURES.append((f"{scene.name} ({precision}, accuracy)", failure))
        table = result.collision_table(native=True)
        bits = 113
    radius = scene.balls[0].body.radius
    time_err, place_err, in_ulps, floor, skipped, after_corner = [], [], [], [], 0, []
    with mpmath.workdps(dps):
        r = mpmath.mpf(radius)
        skip = mpmath.mpf(10) ** (-dps + 10)
        for k in range(1, len(table)):
            prev, row = table[k - 1], table[k]
            x, y, vx, vy = (exact(prev[c]) for c in ("x_i", "y_i", "vx_i_after", "vy_i_after"))
            tau, _ = _cushion_time(scene.boundary, [x, y, vx, vy], r, skip)
            if not tau > mpmath.mpf(10) ** -9:  # a corner: two cushions at one instant
                skipped += 1
                continue
            if k >= 2 and table[k - 2]["t"] == prev["t"]:
                # the flight after a corner: the engine moves the ball off the second cushion first
                # (driver._Run.leave), so it does not start from the recorded place
                px, py = x + vx * tau, y + vy * tau
                miss = mpmath.hypot(exact(row["x_i"]) - px, exact(row["y_i"]) - py)
                after_corner.append(float(miss / (mpmath.hypot(vx, vy) * tau)))
                continue
            t0, t1 = exact(prev["t"]), exact(row["t"])
            err = abs(t1 - t0 - tau)
            time_err.append(float(err / tau))
            in_ulps.append(float(err) / ulp(float(t1), bits))
            floor.append(ulp(float(t1), bits) / 2 / float(tau))
            px, py = x + vx * tau, y + vy * tau
            miss = mpmath.hypot(exact(row["x_i"]) - px, exact(row["y_i"]) - py)
            place_err.append(float(miss / (mpmath.hypot(vx, vy) * tau)))
    nan = float("nan")
    return dict(case=scene.name, precision=precision, impacts=len(table), compared=len(time_err),
                skipped=skipped, t_last=float(table["t"][-1]), failure=failure,
                after_corner=max(after_corner, default=None),
                time_max=max(time_err, default=nan), time_median=float(np.median(time_err)) if time_err else nan,
                floor_max=max(floor, default=nan), ulps_max=max(in_ulps, default=nan),
                place_max=max(place_err, default=nan),
                place_median=float(np.median(place_err)) if place_err else nan)


def two_ball_scene():
    return table_scene(ELLIPSE, [body("0.3", "-0.2", "1.0", "0.7", radius="0.1", mass="0.17"),
                                 body("-0.5", "0.2", "-0.3", "0.5", radius="0.1", mass="0.17")],
                       name="2 balls R = 0.1 in the ellipse")


def global_errors(n: int, with_quad: bool = True) -> list[dict]:
    """The first n impacts of the 2-ball scene (double and quad) against reference_impacts at 50 digits."""
    scene = two_ball_scene()
    double = simulate(scene, t_end=CHUNK_T, max_collisions=n).collision_table()
    quad = simulate(scene, t_end=CHUNK_T, max_collisions=n, precision="quad").collision_table(native=True) \
        if with_quad else double
    ref = reference_impacts(scene, n, dps=50)
    rows = []
    with mpmath.workdps(50):
        for k, x in enumerate(ref):
            same = (int(double["i"][k]), int(double["j"][k])) == (x.i, x.j) == (int(quad["i"][k]), int(quad["j"][k]))
            pos = x.state_after[x.i - 1]
            rows.append(dict(n=k + 1, who=f"{x.i}-{'cushion' if x.j == 0 else x.j}", same=same, t=float(x.t),
                             double=float(abs(exact(double["t"][k]) - x.t) / x.t),
                             quad=float(abs(exact(quad["t"][k]) - x.t) / x.t) if with_quad else None,
                             place=float(mpmath.hypot(exact(double["x_i"][k]) - pos[0],
                                                      exact(double["y_i"][k]) - pos[1]))))
    return rows


def accuracy_section(cfg) -> tuple[list[str], dict]:
    n = cfg["local"]
    cases = [
        one_ball(ELLIPSE, "0", name="particle, ellipse"),
        one_ball(ELLIPSE, "0.1", name="R = 0.1, ellipse"),
        one_ball(ELLIPSE, "0.01", name="R = 0.01, ellipse"),
        one_ball(RECTANGLE, "0.1", name="R = 0.1, rectangle 2 x 1"),
        one_ball(HEXAGON, "0.1", name="R = 0.1, regular hexagon"),
        one_ball(CIRCLE, "0.1", name="R = 0.1, circle"),
    ]
    local = [local_errors(scene, n) for scene in cases]
    local.append(local_errors(one_ball(ELLIPSE, "0.1", name="R = 0.1, ellipse"), cfg["quad"], "quad", 50))
    glob = global_errors(cfg["global"], cfg["global_quad"])
    lines = [
        "## 1. Impact-time accuracy against mpmath",
        "",
        "### Local: each impact predicted from the engine's state after the previous one",
        "",
        f"Launch (x, y) = ({LAUNCH[0]}, {LAUNCH[1]}), v = ({LAUNCH[2]}, {LAUNCH[3]}); solid spheres; reference "
        "`heyroll.reference.billiard._cushion_time` at 40 digits (50 for quad) from the engine's state right "
        "after impact n-1. time error: |t_n - t_(n-1) - tau| / tau (tau the reference's flight time); clock "
        "floor: ulp(t_n)/2 / tau, the rounding of the recorded t_n alone (max over the run); ulps: the time "
        "error in ulps of t_n; place error: |P_n - (P_(n-1) + v tau)| / (|v| tau), the impact place against "
        "the reference's over the chord (no clock in it).",
        "",
        "| case | precision | impacts | t_last s | max time error | median time error | clock floor (max) "
        "| max error in ulp(t_n) | max place error | median place error |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    corners = []
    for r in local:
        note = f" ({r['skipped']} corner hits skipped)" if r["skipped"] else ""
        if r["after_corner"] is not None:
            corners.append(f"{r['case']}: {r['after_corner']:.1e}")
        note += " (the engine stopped early: see the list of engine stops)" if r["failure"] else ""
        lines.append(f"| {r['case']}{note} | {r['precision']} | {r['compared']} | {r['t_last']:.4g} | "
                     f"{r['time_max']:.2e} | {r['time_median']:.2e} | {r['floor_max']:.2e} | {r['ulps_max']:.2f} | "
                     f"{r['place_max']:.2e} | {r['place_median']:.2e} |")
    worst = max(local[:-1], key=lambda r: r["place_max"])
    ulps = max(r["ulps_max"] for r in local[:-1])
    quad = local[-1]
    if ulps <= 4 and worst["place_max"] < 1e-14:
        verdict = (f"Double: every impact is within {ulps:.2f} ulp of its time and its place within "
                   f"{worst['place_max']:.1e} of the chord ({worst['case']}); the time error relative to the flight "
                   "sits at the clock floor, which grows with t (it is the rounding of the absolute time, not of the "
                   "flight).")
    else:
        verdict = (f"Double: **above round-off**: up to {ulps:.3g} ulps of t_n and {worst['place_max']:.1e} of the "
                   f"chord ({worst['case']}): the engine's next impact is not the one its recorded state leads to "
                   "(see 'moves at an impact' in the probes at the end).")
    lines += ["", verdict + f" Quad: max time error {quad['time_max']:.1e}, place error {quad['place_max']:.1e}"
              + (" (~1e-32: the clock floor of quad)." if quad["time_max"] < 1e-30 else " (**above quad round-off**)."),
              ""]
    if corners:
        lines += ["At a corner the ball hits two cushions at one instant (the second impact's flight is 0; skipped). "
                  "The flight after it is left out of the table too: the engine moves the ball off the second cushion "
                  "before it goes on (`_Run.leave`: heyoka would not see a root of an event that starts at zero), so "
                  "it does not start from the recorded place; its place error over the chord: "
                  + "; ".join(corners) + ".", ""]
    lines += [
        f"### Global: the first {len(glob)} impacts of two balls against `reference_impacts`",
        "",
        "Two solid spheres R = 0.1, m = 0.17 in the ellipse, Hedrih's law, k = 1: (0.3, -0.2) v = (1, 0.7) and "
        "(-0.5, 0.2) v = (-0.3, 0.5); `reference_impacts(scene, n, dps=50)` from the initial state: "
        "the error of t_n relative to t_n, in double and in quad, and the distance (m) of ball i's impact "
        "place (double) from the reference's.",
        "",
        "| n | ball-other | same impact | t_n s | rel. error of t_n (double) | rel. error of t_n (quad) "
        "| place error m (double) |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in glob:
        quad_text = "-" if r["quad"] is None else f"{r['quad']:.2e}"
        lines.append(f"| {r['n']} | {r['who']} | {'yes' if r['same'] else 'NO'} | {r['t']:.6f} | {r['double']:.2e} | "
                     f"{quad_text} | {r['place']:.2e} |")
    third = max(1, len(glob) // 3)
    early = max(r["double"] for r in glob[:third])
    late = max(r["double"] for r in glob[-third:])
    lines += [
        "",
        f"The global error grows through the dynamics: max {early:.1e} over the first {third} impacts, "
        f"{late:.1e} over the last {third} (double), the impact places from {glob[0]['place']:.0e} m to "
        f"{max(r['place'] for r in glob[-third:]):.0e} m. Each reflection in the curved cushion and each "
        "ball-ball collision magnifies a deviation of the path (two balls of a billiard scatter like a "
        "dispersing billiard), so the round-off of every impact is amplified by the ones after it; the local "
        "errors above are what the engine controls.",
    ]
    pair = next((k for k, r in enumerate(glob) if "cushion" not in r["who"]), None)
    before = glob[:pair] if pair is not None else glob
    lines.append("")
    if glob[0]["quad"] is None:
        lines += ["Quad: not run in this mode.", ""]
        return lines, dict(local=local, glob=glob)
    lines.append(f"Quad: max {max(r['quad'] for r in before):.1e} over the cushion impacts"
                 + (f" before the first ball-ball collision (n = {pair + 1})." if pair is not None else "."))
    if pair is not None:
        after = max(r["quad"] for r in glob[pair:])
        if after > 1e-25:
            lines[-1] += (f" From that collision on the quad error is {after:.1e} (an mp:200 run gave the same when "
                          "this study was written): a quad or MPFR run rounds the pair's reach (R_i + R_j)^2 to a "
                          "double "
                          "(heyroll/simulation/table/system.py, table_system: the reach is summed and squared at "
                          "mpmath's global 53 bits, outside the model's 256-bit workprec()), so its ball-ball "
                          "impacts are found on a sphere off by ~1e-17 m: an engine bug.")
        else:
            lines[-1] += f" From it on: max {after:.1e}."
    lines.append("")
    return lines, dict(local=local, glob=glob)


# -- 2. speed ----------------------------------------------------------------------------------


def speed_section(cfg) -> tuple[list[str], list[dict]]:
    cases = [(one_ball(ELLIPSE, "0", name="1 particle, ellipse"), cfg["speed_particle"]),
             (one_ball(ELLIPSE, "0.1", name="1 ball R = 0.1, ellipse"), cfg["speed_ball"])]
    cases += [(grid_of_balls(n), cfg["speed_many"]) for n in cfg["speed_sizes"]]
    rows = []
    for scene, n in cases:
        hy.llvm_state.clear_memcache()
        t0 = time.perf_counter()
        failure = run_impacts(scene, n, keep=False, what=f"{scene.name} (speed)").failure
        first = time.perf_counter() - t0
        best = math.inf
        for _ in range(cfg["repeat"]):
            t0 = time.perf_counter()
            got = run_impacts(scene, n, keep=False, what=f"{scene.name} (speed)")
            runs, failure, n_done = got.runs, got.failure or failure, got.impacts
            best = min(best, time.perf_counter() - t0)
        probe = simulate(scene, t_end=CHUNK_T, max_collisions=min(n, 2000))
        cushion = probe.n_cushion / max(probe.n_collisions, 1)
        rows.append(dict(case=scene.name + (" (stopped early: see the list of engine stops)" if failure else ""),
                         impacts=n_done, first=first, compile=max(first - best, 0.0), second=best,
                         rate=n_done / best, runs=runs, cushion=cushion))
    lines = [
        "## 2. Speed",
        "",
        "Impacts per second of a compiled run: first run = compilation + run (heyoka's on-disk cache off, its "
        "in-memory cache cleared before it; heyroll keeps one compiled integrator per scene shape in its process, "
        "so run the script in a fresh process for this column), compile = first - second, second run = the same "
        f"impacts again, best of {cfg['repeat']}; the whole run in pieces of {CHUNK_T:g} s (module docstring), "
        "the restarts included. Balls in the rectangle: R = 0.05, m = 0.17, on a grid, velocities uniform in "
        "[-1, 1]^2 (seed 0), Hedrih's law k = 1.",
        "",
        "| scene | impacts | cushion share | first run s | compile s | second run s | impacts per s | engine calls |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(f"| {r['case']} | {r['impacts']} | {r['cushion']:.2f} | {r['first']:.2f} | {r['compile']:.2f} | "
                     f"{r['second']:.3f} | {r['rate']:.0f} | {r['runs']} |")
    lines.append("")
    return lines, rows


# -- 3. drift ----------------------------------------------------------------------------------


def caustic(x, y, vx, vy, a=A, b=B):
    speed = np.hypot(vx, vy)
    dx, dy = vx / speed, vy / speed
    return a * a * dy * dy + b * b * dx * dx - (x * dy - y * dx) ** 2


def plain_double_loop(n: int, launch=LAUNCH):
    """The same billiard map in plain float64 (no heyoka): the impact by the quadratic formula (the
    stable root), the outward normal grad g / |grad g|, v -> v - 2 (v . n) n. lambda and speed per impact."""
    a2, b2 = A * A, B * B
    x, y, vx, vy = (float(v) for v in launch)
    lam, speed = np.empty(n), np.empty(n)
    for k in range(n):
        qa = vx * vx / a2 + vy * vy / b2
        qb = 2 * (x * vx / a2 + y * vy / b2)
        qc = x * x / a2 + y * y / b2 - 1
        root = math.sqrt(qb * qb - 4 * qa * qc)
        tau = -2 * qc / (qb + root) if qb > 0 else (root - qb) / (2 * qa)
        x, y = x + vx * tau, y + vy * tau
        gx, gy = x / a2, y / b2
        norm = math.sqrt(gx * gx + gy * gy)
        nx, ny = gx / norm, gy / norm
        vn = vx * nx + vy * ny
        vx, vy = vx - 2 * vn * nx, vy - 2 * vn * ny
        s = math.sqrt(vx * vx + vy * vy)
        dx, dy = vx / s, vy / s
        lam[k] = a2 * dy * dy + b2 * dx * dx - (x * dy - y * dx) ** 2
        speed[k] = s
    return lam, speed


def drift_stats(name: str, run: str, values, start: float, checkpoints) -> dict:
    """Drift of ``values`` from ``start``: at the checkpoints, its growth exponent, its sign over ten blocks."""
    drift = values - start
    row = dict(name=name, run=run, value=float(values[0]), points=[])
    for m in checkpoints:
        part = drift[:m]
        row["points"].append(dict(n=m, max=float(np.max(np.abs(part))), end=float(part[-1]),
                                  rms=float(np.sqrt(np.mean(part**2)))))
    lo, hi = row["points"][0], row["points"][-1]
    row["exponent"] = math.log(hi["rms"] / lo["rms"]) / math.log(hi["n"] / lo["n"]) if lo["rms"] > 0 else float("nan")
    # the change over each tenth of the run: an unbiased walk gives both signs, a bias one sign
    edges = np.linspace(0, len(values) - 1, 11).astype(int)
    steps = np.diff(values[edges])
    row["blocks"] = int(np.sum(np.sign(steps) == np.sign(hi["end"])))
    row["per_impact"] = hi["end"] / hi["n"]
    return row


def drift_section(cfg) -> tuple[list[str], dict]:
    n = cfg["drift"]
    scene = one_ball(ELLIPSE, "0", name="particle, ellipse")
    t0 = time.perf_counter()
    got = run_impacts(scene, n, columns=("x_i", "y_i", "vx_i_after", "vy_i_after", "energy_after"),
                      what="particle, ellipse (drift)")
    table, runs, failure = got.table, got.runs, got.failure
    n = len(table["x_i"])
    wall = time.perf_counter() - t0
    x, y, vx, vy = table["x_i"], table["y_i"], table["vx_i_after"], table["vy_i_after"]
    with mpmath.workdps(40):  # the launch's speed and energy from the doubles the engine starts from
        s0 = mpmath.hypot(mpmath.mpf(float(LAUNCH[2])), mpmath.mpf(float(LAUNCH[3])))
        start = {"speed": float(s0), "energy": float(s0 * s0 / 2)}
    t0 = time.perf_counter()
    plain_lam, plain_speed = plain_double_loop(n)
    plain_wall = time.perf_counter() - t0
    checkpoints = [n // 100, n // 10, n]
    lam = caustic(x, y, vx, vy)
    # lambda from its value at the first impact (the launch is not on the cushion)
    rows = [drift_stats("lambda", "engine", lam, lam[0], checkpoints),
            drift_stats("lambda", "plain float64 loop", plain_lam, plain_lam[0], checkpoints),
            drift_stats("speed", "engine", np.hypot(vx, vy), start["speed"], checkpoints),
            drift_stats("speed", "plain float64 loop", plain_speed, start["speed"], checkpoints),
            drift_stats("energy", "engine", table["energy_after"], start["energy"], checkpoints)]
    eps = np.finfo(float).eps
    lines = [
        f"## 3. Drift of the integrals over {n:.0e} impacts",
        "",
        f"Particle in the ellipse, launch (x, y) = ({LAUNCH[0]}, {LAUNCH[1]}), v = ({LAUNCH[2]}, {LAUNCH[3]}), "
        f"{n} impacts in {runs} pieces of {CHUNK_T:g} s ({wall:.1f} s"
        + (f"; the engine stopped {failure}" if failure else "") + "). lambda = a^2 dy^2 + b^2 dx^2 - "
        "(x dy - y dx)^2 at each impact (d the unit outgoing direction; = b^2 - the product of the angular momenta "
        "about the foci), drift from its value at the first impact; speed and energy (= speed^2/2, m = 1) from "
        "the launch's. RMS: over all impacts up to that point. eps = 2.2e-16. For scale, the same map in a "
        f"plain float64 Python loop (`plain_double_loop`: quadratic formula, the same reflection; {plain_wall:.1f} s), "
        "which has no event finding in it.",
        "",
        "| integral | run | value | impacts | max abs drift | drift at the end | RMS drift | max abs drift / eps |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for row in rows:
        for p in row["points"]:
            lines.append(f"| {row['name']} | {row['run']} | {row['value']:.6f} | {p['n']} | {p['max']:.2e} | "
                         f"{p['end']:+.2e} | {p['rms']:.2e} | {p['max'] / eps:.1f} |")
    lines += ["", "Random walk or drift? The RMS drift grows like n^(1/2) for a random walk of round-off, like n for "
              "a bias; and over the ten tenths of the run an unbiased walk changes sign about half the time:", ""]
    for row in rows:
        lo, hi = row["points"][0], row["points"][-1]
        if row["blocks"] >= 9 and row["exponent"] > 0.75:
            kind = "a systematic drift"
        elif row["exponent"] <= 0.75 and row["blocks"] <= 8:
            kind = "a random walk"
        else:
            kind = "between a random walk and a drift"
        lines.append(f"- {row['name']} ({row['run']}): RMS {lo['rms']:.2e} at {lo['n']} impacts, {hi['rms']:.2e} at "
                     f"{hi['n']} (exponent {row['exponent']:.2f}); {row['blocks']} of 10 tenths move it the way of the "
                     f"total; {row['per_impact']:+.1e} per impact ({row['per_impact'] / eps:+.3f} eps): {kind}.")
    engine_lam, plain = rows[0], rows[1]
    ratio = abs(engine_lam["points"][-1]["end"]) / max(abs(plain["points"][-1]["end"]), 1e-300)
    lines += [
        "",
        f"The speed and the energy wander like a random walk of round-off (v_n -> -v_n is rounded at each impact "
        f"and nothing restores |v|): {abs(rows[2]['points'][-1]['end']) / eps:.0f} eps of speed after {n} impacts. "
        f"lambda takes the round-off of the impact place and of the reflected direction; at the end of the run "
        f"the engine's lambda has drifted {ratio:.1f} times as far as the plain loop's. A systematic drift of "
        "lambda (one sign in (nearly) every tenth of the run) would mean a bias of a small fraction of an eps "
        "per impact in where or how the engine reflects (heyoka's root of the event against the quadratic "
        f"formula's); either way lambda's drift is {engine_lam['points'][-1]['max']:.1e} at most over {n} impacts, "
        f"{engine_lam['points'][-1]['max'] / abs(engine_lam['value']):.1e} of its value.",
        "",
    ]
    return lines, dict(rows=rows, wall=wall, runs=runs)


# -- 4. finite ball ----------------------------------------------------------------------------


def integrals_of(table, radius: float) -> dict:
    x, y, vx, vy = table["x_i"], table["y_i"], table["vx_i_after"], table["vy_i_after"]
    lam = caustic(x, y, vx, vy)
    lam_r = caustic(x, y, vx, vy, A - radius, B - radius)
    return dict(lam=lam, lam_r=lam_r, speed=np.hypot(vx, vy), energy=table["energy_after"],
                s=table["boundary_s"], p=np.sin(table["reflection_angle"]))


def finite_ball_section(cfg, figure: Path) -> tuple[list[str], list[dict]]:
    rows, maps = [], {}
    for radius in RADII:
        scene = one_ball(ELLIPSE, radius, name=f"R = {radius}")
        table = run_impacts(scene, cfg["finite"], what=f"R = {radius}, launch {LAUNCH} (integrals)").table
        got = integrals_of(table, float(radius))
        spreads = []
        for x, y, angle in MAP_LAUNCHES:
            launch = (repr(x), repr(y), repr(math.cos(angle)), repr(math.sin(angle)))
            t = run_impacts(one_ball(ELLIPSE, radius, launch=launch), cfg["map"],
                            what=f"R = {radius}, launch ({x:g}, {y:g}) at {angle:.3g} rad (Birkhoff map)").table
            maps.setdefault(radius, []).append(integrals_of(t, float(radius)))
            spreads.append(np.ptp(maps[radius][-1]["lam"]))
        rows.append(dict(radius=radius, impacts=len(table), lam=float(np.mean(got["lam"])),
                         lam_spread=float(np.ptp(got["lam"])), lam_r_spread=float(np.ptp(got["lam_r"])),
                         speed_spread=float(np.ptp(got["speed"])), energy_spread=float(np.ptp(got["energy"])),
                         energy=float(np.mean(got["energy"])), map_median=float(np.median(spreads)),
                         map_max=float(np.max(spreads))))
    draw_birkhoff(maps, figure)
    kept = max(max(r["speed_spread"], r["energy_spread"]) for r in rows)
    lines = [
        "## 4. A finite ball in the ellipse: which integrals are lost",
        "",
        f"Solid sphere, m = 1, rolling cushion k = 1, launch (x, y) = ({LAUNCH[0]}, {LAUNCH[1]}), "
        f"v = ({LAUNCH[2]}, {LAUNCH[3]}), {cfg['finite']} impacts per R (R = 0: the particle). The centre moves "
        "inside the inner parallel curve at distance R of the ellipse (a curve of degree 8, not a conic), and "
        "reflects there as a point billiard. Spread = max - min over the impacts. lambda(a, b): the "
        "particle's caustic parameter with the table's a, b (= b^2 - the product of the focal angular momenta, "
        "so that product is lost with it); lambda(a-R, b-R): the same for the ellipse nearest the centre's "
        f"curve. Map launches: the {len(MAP_LAUNCHES)} launches of the figure, {cfg['map']} impacts each: the median "
        "and max of their lambda(a, b) spreads.",
        "",
        "| R | impacts | mean lambda(a, b) | spread lambda(a, b) | spread lambda(a-R, b-R) | spread speed "
        "| spread energy | energy J | map launches: median spread lambda | max |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(f"| {r['radius']} | {r['impacts']} | {r['lam']:.6f} | {r['lam_spread']:.2e} | "
                     f"{r['lam_r_spread']:.2e} | {r['speed_spread']:.2e} | {r['energy_spread']:.2e} | "
                     f"{r['energy']:.6f} | {r['map_median']:.2e} | {r['map_max']:.2e} |")
    lines += [
        "",
        f"Lost for R > 0: lambda, in either form (and with it the focal product and Joachimsthal's integral, "
        f"which all single out the confocal family of a conic): its spread goes from {rows[0]['lam_spread']:.0e} at "
        f"R = 0 to {rows[1]['lam_spread']:.1e}, {rows[2]['lam_spread']:.1e}, {rows[3]['lam_spread']:.1e} "
        f"(of a value ~2) at R = {RADII[1]}, {RADII[2]}, {RADII[3]}. Kept for every R: the speed and the energy "
        "(a rolling ball's kinetic energy m kappa v^2 / 2, kappa = 7/5): the rolling cushion reverses v_n and "
        f"keeps the rest; their spread stays below {kept:.0e}.",
        "",
        f"![Birkhoff maps against R]({figure.name})",
        "",
        "The Birkhoff map (arc length s of the contact point on the cushion, from (a, 0) counter-clockwise; "
        "sin of the angle between the outgoing velocity and the inward normal) of the figure's launches. "
        "R = 0: every orbit lies on an invariant curve (a level set of lambda): rotations above and below, "
        "librations in the islands about the minor axis' 2-periodic orbit, and the separatrix through the "
        "orbits along the major axis. As R grows (the figure of the default run): the curves near the separatrix "
        "break up into a chaotic layer (R = 0.05) that widens until it fills most of the rotation region "
        "(R = 0.2, 0.4); chains of islands appear among the rotations (R = 0.05) and around the librations "
        "(R = 0.4); the island of librations about the minor axis' 2-periodic orbit (the stable one) persists "
        "at every R; and invariant curves close to |sin| = 1 (whispering gallery) survive, closer to 1 as R "
        "grows (the centre's curve is nearly cusped at R = 0.4: its least radius of curvature is b^2/a - R = 0.1), as "
        "Lazutkin's theorem says for a smooth strictly convex curve.",
        "",
    ]
    return lines, rows


def draw_birkhoff(maps: dict, path: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(12, 8.5), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 2, sharex=True, sharey=True)
    colours = [f"C{k}" for k in range(10)]
    for ax, (radius, orbits) in zip(axes.flat, maps.items()):
        for k, orbit in enumerate(orbits):
            ax.plot(orbit["s"], orbit["p"], ",", color=colours[k % 10], alpha=0.8, rasterized=True)
        ratio = float(radius) * A / B**2
        ax.set_title(f"R = {radius}" + (" (particle)" if ratio == 0 else f" (R a / b^2 = {ratio:.2f})"))
        ax.set_xlim(0, max(float(np.nanmax(o["s"])) for o in orbits))
        ax.set_ylim(-1, 1)
    for ax in axes[1]:
        ax.set_xlabel("s: arc length of the contact point from (a, 0) (m)")
    for ax in axes[:, 0]:
        ax.set_ylabel("sin(reflection angle)")
    fig.suptitle("Birkhoff map of a ball in the ellipse a = 2, b = 1 as its radius R grows "
                 f"({len(next(iter(maps.values())))} launches, one colour each)")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)


# -- main --------------------------------------------------------------------------------------


MODES = {
    "default": dict(local=200, quad=100, global_=20, global_quad=True, speed_particle=50_000, speed_ball=10_000,
                    speed_many=10_000, speed_sizes=(4, 16), repeat=2, drift=1_000_000, finite=2000, map=2000,
                    ride=10_000, skid_times=(0.02, 0.05, 0.1, 0.14), onsets=(18, 22, 26, 30, 34), random_scenes=100,
                    crowded=16),
    "quick": dict(local=200, quad=50, global_=20, global_quad=True, speed_particle=20_000, speed_ball=5000,
                  speed_many=4000, speed_sizes=(4, 16), repeat=1, drift=100_000, finite=2000, map=800, ride=1000,
                  skid_times=(0.05, 0.14), onsets=(18, 22, 26, 30), random_scenes=30, crowded=6),
    "tiny": dict(local=30, quad=15, global_=8, global_quad=False, speed_particle=2000, speed_ball=500,
                 speed_many=500, speed_sizes=(4,), repeat=1, drift=10_000, finite=300, map=150, ride=50,
                 skid_times=(0.05,), onsets=(22, 26), random_scenes=3, crowded=2),
}


def riding_section(cfg) -> tuple[list[str], list[dict]]:
    """Section 5 (module docstring): settle, then ride for cfg["ride"] seconds, against reference_ride."""
    ride = float(cfg["ride"])
    rows = []
    for boundary, radius, label in ((CIRCLE, "0.1", "ball R = 0.1, circle"), (ELLIPSE, "0", "particle, ellipse"),
                                    (ELLIPSE, "0.1", "ball R = 0.1, ellipse"),
                                    (ELLIPSE, "0.01", "ball R = 0.01, ellipse")):
        scene = one_ball(boundary, radius, name=label, cushion_k="0.5")
        first = simulate(scene, t_end=CHUNK_T)  # to the settle (a few impacts; k = 0.5)
        table = first.collision_table()
        settled = np.flatnonzero(table["law_flag"] == 4)
        if not len(settled):
            FAILURES.append((label, f"no settle within {CHUNK_T:g} s: {first.status.value} {first.message}"))
            continue
        t0, state = next((t, s) for t, s, _a, riding in first.paths if 0 in riding)
        started = time.perf_counter()
        run = simulate(scene, t_end=t0 + ride)
        wall = time.perf_counter() - started
        x, y, vx, vy = (float(v) for v in run.state_final[:4])
        a, b = (float(scene.boundary.a), float(scene.boundary.b)) if scene.boundary.kind == "ellipse" else (1.0, 1.0)
        rx, ry = reference_ride(a, b, radius, *state[:4], mpmath.mpf(t0 + ride) - mpmath.mpf(t0))
        with mpmath.workdps(40):
            d = _ellipse_distance(mpmath.mpf(a), mpmath.mpf(b), mpmath.mpf(x), mpmath.mpf(y))[0] - mpmath.mpf(radius)
        speed0 = math.hypot(state[2], state[3])
        rows.append(dict(label=label, impacts=int(settled[0]), t_settle=float(table["t"][settled[0]]),
                         loss=float(table["energy_before"][settled[0]] - table["energy_after"][settled[0]]),
                         error=math.hypot(x - float(rx), y - float(ry)), speed=math.hypot(vx, vy) / speed0 - 1,
                         distance=float(d), wall=wall, status=run.status.value, laps=speed0 * ride / scene.boundary.perimeter()))
    lines = ["## 5. Settling onto the cushion and riding it (k = 0.5)", "",
             f"Launch (0.3, -0.2), v = (1, 0.7), cushion `rolling`, k = 0.5; after the settle a ride of {ride:g} s "
             "against `reference_ride` (40 digits) from the engine's state right after the settle.", "",
             "| case | impacts before the settle | settle at t (s) | energy of the settle row (J) | laps ridden | "
             "end position error (m) | speed change (rel.) | distance from the curve at the end (m) | wall s | status |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['label']} | {r['impacts']} | {r['t_settle']:.6g} | {r['loss']:.2e} | {r['laps']:.0f} | "
                     f"{r['error']:.1e} | {r['speed']:.1e} | {r['distance']:.1e} | {r['wall']:.3f} | {r['status']} |")
    lines += ["", "The settle row takes what the rest of the accumulation would dissipate (1/2 kappa m v_n^2 with "
              "v_n below about 1e-6 of the speed). On the circle and for the particle the curve of the centre is a "
              "conic; for a finite ball in the ellipse it is the degree-8 polynomial, whose round-off grows as R "
              "shrinks (its inner and outer branches close in): the ride's error follows it.", ""]
    return lines, rows


def slipping_body(x, y, vx, vy, ux, uy, radius=0.1) -> dict:
    """A ball with velocity v and slip u (its spin from w = v - u = R (omega_y, -omega_x))."""
    wx, wy = vx - ux, vy - uy
    return dict(body(repr(x), repr(y), repr(vx), repr(vy), radius=repr(radius), mass="0.17"), wx=repr(-wy / radius),
                wy=repr(wx / radius))


def skid_section(cfg) -> tuple[list[str], dict]:
    """Section 6 (module docstring): skids against reference_skid / reference_skid_end; the grip-loss onset."""
    from heyroll.reference.billiard import reference_skid, reference_skid_end
    from heyroll.simulation.precision import DOUBLE
    from heyroll.simulation.table import driver as table_driver
    from heyroll.simulation.table.system import table_system

    kappa, mu_g = mpmath.mpf(7) / 5, mpmath.mpf("0.2") * mpmath.mpf("9.81")
    start = slipping_body(0.9, 0.0, 0.0, 1.0, 0.0, 1.0)
    lines = ["## 6. Skidding along the cushion (`slide` cushion, mu = 0.2)", "",
             "A ball (R = 0.1, solid sphere) started on a circular cushion (R_t = 1) at (0.9, 0) with v = (0, 1) and "
             "no spin (slip u = v): it skids, its slip ends, it rolls on along the cushion. Max. abs. error of "
             "(x, y, vx, vy, ux, uy) against `reference_skid` (30 digits):", "",
             "| t (s) | state error | steps |", "|---|---|---|"]
    out = {}
    for t in cfg["skid_times"]:
        run = simulate(table_scene(CIRCLE, [start], cushion="slide", cushion_k="0.5", name="skid"), t_end=t)
        reference = reference_skid(0.9, kappa, mu_g, *run.state_initial[:6], t)
        error = max(abs(float(r) - e) for r, e in zip(reference, run.state_final))
        lines.append(f"| {t:g} | {error:.1e} | {run.steps} |")
        out[f"skid_{t}"] = error
    from heyroll.simulation.driver import RunOptions
    t = cfg["skid_times"][0]
    run = simulate(table_scene(CIRCLE, [start], cushion="slide", cushion_k="0.5", name="skid"),
                   RunOptions(precision="quad", t_end=t))
    with mpmath.workdps(50):
        reference = reference_skid("0.9", mpmath.mpf(7) / 5, mpmath.mpf("0.2") * mpmath.mpf("9.81"), "0.9", 0, 0, 1, 0, 1,
                                   t, dps=45)
        error = max(abs(mpmath.mpf(str(e)) - r) for r, e in zip(reference, run.state_final))
    out["skid_quad"] = float(error)
    lines.append(f"| {t:g} (quad; reference at 45 digits) | {float(error):.1e} | {run.steps} |")
    scene = table_scene(CIRCLE, [start], cushion="slide", cushion_k="0.5", name="skid")
    run = simulate(scene, t_end=1.0)
    system = table_system(scene, DOUBLE)
    slip_end = system.pars[system.slip_end]
    t_ref, *state = reference_skid_end(0.9, kappa, mu_g, *run.state_initial[:6], slip_end)
    t_roll, rolling, _acc, _riding = next(p for p in run.paths if p[0] > 0 and p[1][4:6] == [0.0, 0.0])
    out["slip_end_time"] = abs(t_roll - float(t_ref))
    out["slip_end_state"] = max(abs(float(r) - e) for r, e in zip(state[:4], rolling[:4]))
    lines += ["", f"The slip falls to SLIP_END = {slip_end:.3g} m/s at t = {t_roll:.17g} s: `reference_skid_end` "
              f"(30 digits) differs by {out['slip_end_time']:.1e} s; the state (x, y, vx, vy) there by "
              f"{out['slip_end_state']:.1e}."]
    lifting = slipping_body(0.9, 0.0, 0.0, 1.5, 3.0, 3.0)
    run = simulate(table_scene(CIRCLE, [lifting], cushion="slide", cushion_k="0.5", name="lift"), t_end=0.3)
    t_lift, lifted, _acc, riding = run.paths[1]
    *state, nu = reference_skid(0.9, kappa, mu_g, *run.state_initial[:6], t_lift)
    out["lift_push"] = float(nu)
    lines += ["", f"A slip u = (3, 3) m/s at v = (0, 1.5) m/s (friction drawing the ball off): the engine's lift-off at "
              f"t = {t_lift:.17g} s; the reference's cushion push there {float(nu):.1e} m/s^2 (0 at the exact "
              f"lift-off; it falls at ~10 m/s^3); state error {max(abs(float(r) - e) for r, e in zip(state, lifted)):.1e}.",
              "", "### The loss of grip: SKID_ONSET", "",
              "A ball (R = 0.05) started on the ellipse's centre curve at (0, 0.95), v = (1, 0): under the `slide` cushion "
              "with mu = 0.05 it rolls while 0.4 v^2/rho_c <= mu g and loses its grip where the curve tightens "
              "(rho_c = 0.815 m), skids, rolls again. The state where that first skid's slip ends, for several "
              "SKID_ONSET (the slip, relative to the top speed, the skid starts with; the ball rolls on until its slip "
              "would be that), against the smallest:", "",
              "| SKID_ONSET | slip end t (s) | state difference | steps | wall s |", "|---|---|---|---|---|"]
    along = body("0", "0.95", "1", "0", radius="0.05", mass="0.17")
    scene = table_scene(ELLIPSE, [along], cushion="slide", cushion_k="0.8", friction="0.05", name="grip")
    rows = []
    saved = table_driver.SKID_ONSET
    try:
        for exponent in cfg["onsets"]:
            table_driver.SKID_ONSET = 2.0**-exponent
            started = time.perf_counter()
            run = simulate(scene, t_end=4.0)
            wall = time.perf_counter() - started
            first = next(n for n, p in enumerate(run.paths) if p[1][4:6] != [0.0, 0.0])
            t_end, ended, _acc, _riding = next(p for p in run.paths[first:] if p[1][4:6] == [0.0, 0.0])
            rows.append((exponent, t_end, ended, run.steps, wall))
    finally:
        table_driver.SKID_ONSET = saved
    best = rows[-1][2]
    for exponent, t_end, ended, steps, wall in rows:
        difference = max(abs(a - b) for a, b in zip(ended[:4], best[:4]))
        lines.append(f"| 2^-{exponent} | {t_end:.12f} | {difference:.1e} | {steps} | {wall:.3f} |")
        out[f"onset_{exponent}"] = difference
    lines += ["", f"heyroll uses 2^-{round(-math.log2(saved))}. The difference falls a little faster than SKID_ONSET "
              "(the skid's friction missed while the ball rolls on; estimated ~SKID_ONSET^1.5, measured here ~1.2), the "
              "steps grow as SKID_ONSET^-0.5 (the slip's direction relaxes at a rate nu/|u| from the onset).", ""]
    return lines, out


def random_dissipative_scene(rng) -> tuple:
    """One seeded random scene of section 7 (module docstring): (description, scene)."""
    boundary = rng.choice(["ellipse", "circle", "ellipse", "rectangle"])
    text = {"ellipse": ELLIPSE, "circle": CIRCLE, "rectangle": 'boundary = "rectangle"\nwidth = 3.0\nheight = 1.6'}
    cushion, cushion_k = rng.choice(["slide", "slide", "rolling"]), round(rng.uniform(0.3, 0.95), 3)
    friction, law = round(rng.uniform(0.02, 0.3), 3), rng.choice(["hedrih", "newton", "slide"])
    balls = []
    while len(balls) < rng.choice([1, 1, 2, 3]):
        x, y = rng.uniform(-1.2, 1.2), rng.uniform(-0.6, 0.6)
        if boundary == "circle":
            x *= 0.6
        if all((x - float(b["x"])) ** 2 + (y - float(b["y"])) ** 2 > 0.25**2 for b in balls):
            speed, angle = rng.uniform(0.3, 3.0), rng.uniform(0, 2 * math.pi)
            balls.append(body(repr(x), repr(y), repr(speed * math.cos(angle)), repr(speed * math.sin(angle)),
                              mass="0.17"))
    scene = table_scene(text[boundary], balls, law=law, name="random", cushion_k=str(cushion_k), cushion=cushion,
                        friction=str(friction))
    return f"{boundary}, {len(balls)} ball(s), cushion {cushion} k={cushion_k}, mu={friction}, law {law}", scene


def random_scenes_section(cfg) -> tuple[list[str], dict]:
    """Section 7 (module docstring): statuses and wall times of seeded random dissipative scenes."""
    import random
    from collections import Counter

    rng = random.Random(2026)
    tally, walls, slowest = Counter(), [], (0.0, "")
    for _ in range(cfg["random_scenes"]):
        what, scene = random_dissipative_scene(rng)
        started = time.perf_counter()
        result = simulate(scene, t_end=30.0, max_collisions=20_000)
        wall = time.perf_counter() - started
        walls.append(wall)
        slowest = max(slowest, (wall, what))
        tally[(result.status.value, result.message.split(" at t")[0].split(" after ")[0][:60])] += 1
    lines = ["## 7. Random dissipative scenes", "",
             f"{cfg['random_scenes']} seeded random scenes (module docstring), 30 s each, max_collisions 20,000:", "",
             "| runs | status | message |", "|---|---|---|"]
    lines += [f"| {n} | {status} | {message} |" for (status, message), n in tally.most_common()]
    lines += ["", f"Wall time per scene: median {float(np.median(walls)):.2f} s, total {sum(walls):.1f} s; slowest "
              f"{slowest[0]:.1f} s ({slowest[1]}).", ""]
    return lines, {"tally": dict(tally), "walls": walls}


def rack_scene(rng, index: int) -> tuple:
    """One seeded crowded scene of section 8: a pool break (a 15-ball rack 2 R + gap apart, the cue ball with
    follow, stun or draw) or a cradle (five balls touching in a row, the first struck with follow or draw), with
    a dissipative mix of laws, restitutions, cushion models and friction. Returns (description, scene)."""
    radius, gap = 0.028575, rng.choice([0.0, 1e-13, 1e-9])
    law, k = rng.choice(["hedrih", "newton", "slide"]), rng.choice(["0", "0.3", "0.9", "0.95"])
    cushion, cushion_k, friction = rng.choice(["slide", "rolling"]), rng.choice(["0.3", "0.9"]), rng.choice(
        ["0.05", "0.2"])
    spin = rng.choice([-100.0, 0.0, 100.0])  # draw, stun, follow (w_y: u = v - R w_y along x)
    balls = []
    if index % 2 == 0:
        d = 2 * radius + gap
        for row in range(5):
            for j in range(row + 1):
                # (spread by 1e-14 about the apex: sqrt(3)'s rounding made neighbours overlap by 1e-17)
                x, y = 0.635 + row * d * math.sqrt(3) / 2 * (1 + 1e-14), (j - row / 2) * d * (1 + 1e-14)
                balls.append(body(repr(x), repr(y), "0", "0", radius=repr(radius), mass="0.17"))
        speed, what = rng.uniform(3, 8), "break"
        cue = dict(body("-0.635", repr(rng.choice([0.0, 0.005])), repr(speed), "0", radius=repr(radius),
                        mass="0.17"), wx=0.0, wy=spin)
        track = 'boundary = "rectangle"\nwidth = 2.54\nheight = 1.27'
    else:
        for n in range(4):
            balls.append(body(repr(n * (2 * radius + gap)), "0", "0", "0", radius=repr(radius), mass="0.17"))
        speed, what = rng.uniform(0.5, 2), "cradle"
        cue = dict(body("-0.3", "0", repr(speed), "0", radius=repr(radius), mass="0.17"), wx=0.0, wy=spin)
        track = 'boundary = "rectangle"\nwidth = 1.6\nheight = 0.8'
    balls.insert(0, cue)
    policy = rng.choice(["sequential", "impulses"])
    scene = table_scene(track, balls, law=law, name=what, cushion_k=cushion_k, cushion=cushion, friction=friction,
                        k=k, simultaneous=policy)
    spin_name = {-100.0: "draw", 0.0: "stun", 100.0: "follow"}[spin]
    return (f"{what} ({len(balls)} balls, {spin_name}, gap {gap:g}), law {law} k={k} {policy}, cushion {cushion} "
            f"k={cushion_k}, mu={friction}"), scene


def crowded_section(cfg) -> tuple[list[str], dict]:
    """Section 8 (rack_scene): statuses, bonds made and wall times of seeded breaks and cradles."""
    import random
    from collections import Counter

    rng = random.Random(7)
    tally, walls, rows, slowest = Counter(), [], [], (0.0, "")
    for index in range(cfg["crowded"]):
        what, scene = rack_scene(rng, index)
        started = time.perf_counter()
        result = simulate(scene, t_end=5.0, max_collisions=20_000)
        wall = time.perf_counter() - started
        walls.append(wall)
        slowest = max(slowest, (wall, what))
        table = result.collision_table()
        bonds = int(np.sum((table["law_flag"] == 4) & (table["j"] > 0))) if len(table["t"]) else 0
        tally[(result.status.value, result.message.split(" at t")[0].split(" after ")[0][:70])] += 1
        gain = float(np.max(table["energy_after"] - table["energy_before"], initial=0.0))
        rows.append(f"| {what} | {result.status.value} | {result.n_collisions} | {bonds} | "
                    f"{gain / result.energy_initial:.1e} | {wall:.1f} |")
    lines = ["## 8. Crowded tables: breaks and cradles", "",
             f"{cfg['crowded']} seeded scenes (rack_scene: a 15-ball rack and a cue ball with follow, stun or draw; "
             "five balls in a row), 5 s each, max_collisions 20,000. Balls that friction keeps driving together are "
             "pressed together into clusters of bonds (README, 'Clusters'); 'bonds made' counts the pair rows with "
             "law_flag 4; 'largest rise' is the largest energy rise of a row over the initial energy (round-off).", "",
             "| scene | status | impacts | bonds made | largest rise | wall (s) |", "|---|---|---|---|---|---|"]
    lines += rows
    lines += ["", "| runs | status | message |", "|---|---|---|"]
    lines += [f"| {n} | {status} | {message} |" for (status, message), n in tally.most_common()]
    lines += ["", f"Wall time per scene: median {float(np.median(walls)):.2f} s, total {sum(walls):.1f} s; slowest "
              f"{slowest[0]:.1f} s ({slowest[1]}). A run compiles one system per shape of its bonds (0.1-0.2 s "
              "each for 16 balls).", ""]
    return lines, {"tally": dict(tally), "walls": walls}


def source_state() -> str:
    """The commit of the package and whether heyroll/ has uncommitted edits (read-only git calls)."""
    import subprocess

    import heyroll

    root = Path(heyroll.__file__).resolve().parents[1]
    if not (root / ".git").exists():
        return f"source: heyroll imported from {root} (not a git checkout)"
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=root, capture_output=True, text=True,
                              timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--", "heyroll"], cwd=root, capture_output=True,
                               text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "source: unknown (no git)"
    if not head:
        return "source: unknown (no git)"
    return f"source: commit {head}" + (f", with uncommitted edits in heyroll/ ({len(dirty.splitlines())} files)"
                                       if dirty else "")


def probes(tiny: bool = False) -> list[str]:
    """Two engine defects found while writing this study, probed on the engine as it is now."""
    lines = ["## Probes of engine defects met while writing this study", ""]
    cases = [(one_ball(CIRCLE, "0.1", name="ball R = 0.1 on the circle"), 1e5, 1e5 / 1000 * 731)]
    if not tiny:
        cases.append((one_ball(ELLIPSE, "0", name="the particle of section 3"), 1e6, 1e6 / 1.736))
    for scene, t_end, expected in cases:
        long = simulate(scene, t_end=t_end, max_collisions=None)
        inside = on_table(scene, long.state_final)
        lines.append(
            f"- Long steps: {scene.name} in one run to t_end = {t_end:.0e} s: status {long.status.value}, "
            f"{long.n_collisions} impacts (about {expected:.0f} expected), final centre "
            f"({float(long.state_final[0]):.3g}, {float(long.state_final[1]):.3g}) "
            + ("on the table: fine." if inside else
               "**off the table**: cushion impacts were missed (heyoka: 'polynomial root finding during event "
               "detection failed') and the run still ends 'completed'. heyroll/simulation/table/driver.py calls "
               "ta.propagate_until(t_end) without max_delta_t, so a step of a straight-line motion is as long as "
               "the time left to t_end, and nothing checks the final state for overlap. This study runs in "
               f"pieces of {CHUNK_T:g} s (`run_impacts`)."))
    moves = []
    for radius, boundary, label in (("0", ELLIPSE, "particle, ellipse"), ("0.1", ELLIPSE, "R = 0.1, ellipse"),
                                    ("0.01", ELLIPSE, "R = 0.01, ellipse"), ("0.1", CIRCLE, "R = 0.1, circle"),
                                    ("0.1", RECTANGLE, "R = 0.1, rectangle")):
        sc = one_ball(boundary, radius)
        worst = 0.0
        for k in range(1, 6):
            first = simulate(sc, t_end=CHUNK_T, max_collisions=k)
            row = first.collision_table()[-1]
            worst = max(worst, math.hypot(float(first.state_final[0]) - row["x_i"],
                                          float(first.state_final[1]) - row["y_i"]))
        moves.append(f"{label} {worst:.1e} m")
    corner = table_scene(RECTANGLE, [body("0.0", "0.0", "0.95", "0.45", radius="0.05")], name="corner")
    hit = simulate(corner, t_end=5, max_collisions=2)
    row = hit.collision_table()[-1]
    moves.append(f"and a ball R = 0.05 into a corner of the rectangle (two cushions at t = 1 s) "
                 f"{math.hypot(float(hit.state_final[0]) - row['x_i'], float(hit.state_final[1]) - row['y_i']):.1e} m")
    lines.append("- Moves at an impact: an impact changes velocities only; the largest distance between the "
                 "recorded place of each of the first 5 impacts and the centre the engine goes on from (a run "
                 "stopped right after it): " + ", ".join(moves) + ".")
    ellipse = one_ball(ELLIPSE, "0.4").boundary
    x, y = -1.3137518502318222, -0.30714794704282095  # a centre the R = 0.4 runs met (see the stops above)
    guess, tol = -0.5668176139419914, 2.0**-27  # as contacts.ContactGeometry.exact_wall passes them in double
    found = ellipse.exact_distance(x, y, 4.0, 1.0, 0.0, guess, tol)[0] - 0.4
    with mpmath.workdps(40):
        true = float(_ellipse_distance(mpmath.mpf(2), mpmath.mpf(1), mpmath.mpf(x), mpmath.mpf(y))[0]
                     - mpmath.mpf("0.4"))
    lines.append(
        f"- Foot point: EllipseBoundary.exact_distance at the centre ({x!r}, {y!r}) (a = 2, b = 1, R = 0.4, "
        f"guess {guess!r}, tol 2^-27, as the polish of an impact calls it): distance - R = {found:.3g} m against "
        f"{true:.3g} m (mpmath)"
        + (": fine." if abs(found - true) < 1e-13 else
           ". **Wrong**: its Newton step lands on the root to below an ulp (new == lam), where the value is "
           "-1e-16 and the bracket's upper end was just set to lam, so `lo < new < hi` fails and the loop bisects "
           "back to the middle of a stale bracket (2e-9 away), then takes that for converged (step < tol |lam| "
           "and < previous/2). The polish (_Run.polish) then moves the impact by ~1e-8 s: an overlap of "
           "~3e-9 m stops the run (the 'Engine stops' above); with the stale end on the other side (a value of "
           "+1e-16) the same slip would make the ball reflect before its cushion, unflagged. Scene: this ball "
           "(x, y) = (1.4165877768793114, -0.0962310802555661), "
           "v = (-0.9476787997412875, 0.31922545719432815), t_end = 500: status overlap at t = 258.41 s, "
           "impact 191."))
    odd = table_scene('boundary = "ellipse"\na = 2.1\nb = 1.3', [body(*LAUNCH, radius="0.1")], name="a = 2.1, b = 1.3")
    quad = simulate(odd, t_end=100, max_collisions=30, precision="quad")
    ok = quad.status is Status.MAX_COLLISIONS
    lines.append(
        f"- Quad with a^2, b^2 not doubles: a ball R = 0.1 in the ellipse a = 2.1, b = 1.3, precision quad, 30 "
        f"impacts: status {quad.status.value} after {quad.n_collisions} impacts"
        + (": fine." if ok else
           f" ({quad.message}). heyroll/simulation/table/contacts.py (ContactGeometry.__init__) takes a^2 and b^2 "
           "for the foot-point polish at mpmath's global 53 bits (`num(self.boundary.a ** 2)`, outside "
           "workprec()), so in quad or MPFR every polished impact lands on a slightly different ellipse than "
           "the gap polynomial's; the same run inside `mpmath.workprec(256)` goes through."))
    lines.append("")
    return lines


def main(argv=None) -> str:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--quick", action="store_true", help="1e5 impacts of drift, shorter runs (< 3 min)")
    mode.add_argument("--tiny", action="store_true", help="a smoke test of every section (for tests)")
    parser.add_argument("--drift", type=int, default=None, help="impacts of the drift study (default 1e6)")
    parser.add_argument("--output", type=Path, default=REPORT, help="the markdown report; the figure goes beside it")
    args = parser.parse_args(argv)
    name = "tiny" if args.tiny else "quick" if args.quick else "default"
    cfg = dict(MODES[name])
    cfg["global"] = cfg.pop("global_")
    if args.drift is not None:
        cfg["drift"] = args.drift
    figure = args.output.parent / FIGURE_NAME
    started = time.perf_counter()
    FAILURES.clear()
    cache = hy.llvm_state.get_diskcache_enabled()
    hy.llvm_state.set_diskcache_enabled(False)
    try:
        speed, _ = speed_section(cfg)  # first: the scenes' shapes are compiled here
        accuracy, _ = accuracy_section(cfg)
        drift, _ = drift_section(cfg)
        finite, _ = finite_ball_section(cfg, figure)
        riding, _ = riding_section(cfg)
        skidding, _ = skid_section(cfg)
        randomly, _ = random_scenes_section(cfg)
        crowded, _ = crowded_section(cfg)
        probed = probes(tiny=name == "tiny")
    finally:
        hy.llvm_state.set_diskcache_enabled(cache)
    elapsed = time.perf_counter() - started
    flag = {"tiny": " --tiny", "quick": " --quick", "default": ""}[name]
    extra = f" --drift {args.drift}" if args.drift is not None else ""
    head = [
        "# Billiards (paper section 7): accuracy, speed, drift of the integrals, what a finite ball loses",
        "",
        f"`python validation/billiards.py{flag}{extra}` ({elapsed / 60:.1f} min, mode {name}). Ellipse a = 2, b = 1 "
        "throughout; double unless said otherwise; cushion `rolling`, k = 1.",
        "",
        f"Machine: shared and noisy, {os.cpu_count()} cores, one used: wall times vary by tens of per cent from run "
        f"to run (compare rows of one report, not reports). Versions: {versions()}; {source_state()}.",
        "",
        "Every run here is cut into pieces of at most "
        f"{CHUNK_T:g} s, each restarted from where the last one ended and checked to end on the table: "
        + ("in one long run a particle in the ellipse (or a ball on a circular table) misses cushion impacts (see "
           "the probes at the end)." if any("**off the table**" in line for line in probed) else
           "at commit 9b0f749 one long run of a particle in the ellipse (or a ball on a circular table) missed "
           "cushion impacts; the probes at the end find that fixed in the engine run here."),
        "",
    ]
    stops = ["## Engine stops in this study's runs", ""]
    stops += [f"- {what}: {message}" for what, message in FAILURES] or ["None: every run reached its impact count."]
    stops.append("")
    text = "\n".join(head + accuracy + speed + drift + finite + riding + skidding + randomly + crowded + stops + probed)
    publish(text, args.output)
    return text


if __name__ == "__main__":
    main()
