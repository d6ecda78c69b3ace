"""Run a scene on an arc chain or a curve y = f(x) (paper sections 5-6).

One heyoka integrator, terminal events only; each event stops the
integration and is resolved here:

* ``upper``/``lower`` at a junction of an arc chain: the body's piece
  parameters switch to the next piece; the state does not change.
* ``upper``/``lower`` at an end of the track: a limiter, an impact with a
  fixed stop, v -> -k v (the one-body limit of the rolling law, m_2 -> oo).
* ``gap``: a collision of neighbours, resolved by the scene's law on the
  local rates (omega_P = |dC/dq| q'/r for the rolling law), checked for
  consistency (the bodies must separate), with the scene's policy when not.

Persistent contact (an accumulating sequence of impacts) is not modelled on
these tracks yet: the run stops with status ``contact`` and says where.
"""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass, field

import heyoka as hy
import mpmath
import numpy as np

from ..model.path_scene import PathScene, piece_index
from ..model.paths import CurveTrack
from .path_system import FLOAT_TYPES, PathSystem, to_float
from .result import Status

#: Impacts of one kind closer than this (in units of the motion's time scale)
#: this many times in a row are an accumulating (Zeno) sequence.
ZENO_INTERVAL = 1e-12
ZENO_REPEATS = 8
#: Or: consecutive intervals shrink by a ratio below ZENO_RATIO and the rest of
#: their geometric series lasts less than this (in units of the time scale).
ZENO_RATIO = 0.99
ZENO_REMAINING = 1e-7
#: An outgoing gap rate below -this * |incoming| means the law left the bodies approaching.
CONSISTENCY_TOLERANCE = 64 * np.finfo(float).eps
#: A collision leaving the gap opening slower than this fraction of its closing
#: speed (k ~ 0) may leave the bodies pressed together: probe for it.
SEPARATION = 1e-6
#: ... and so may one that arrives slower than this fraction of g T (T the
#: motion's time scale): bodies chattering at rest against each other.
SLOW_APPROACH = 1e-6
#: Deeper than this (m) at any stop, a pair overlaps: the run says so.
OVERLAP_TOLERANCE = 1e-12

LIMITER_COLUMNS = ("t", "body", "end", "q", "v_before", "v_after")
COLLISION_COLUMNS = ("n", "t", "i", "j", "q_i", "q_j", "v_i_before", "v_j_before", "v_i_after", "v_j_after",
                     "omega_i_before", "omega_j_before", "omega_i_after", "omega_j_after",
                     "energy_before", "energy_after", "law_flag")


class LocalMetric:
    """The track seen by a collision law at one instant: |dC/dq| = sigma.

    On the circle sigma = R - r and the laws' formulas (omega_P = (R - r)/r
    phi', v_C = (R - r) phi', generalized mass kappa m (R - r)^2) are those
    of section 4; on any track they read omega_P = sigma q'/r, v_C = sigma q'
    and kappa m sigma^2 (paper eqs. 98, 100: omega_P = v_C,rel / r).
    """

    def __init__(self, sigma: float):
        self.sigma = mpmath.mpf(sigma)

    def rolling_ratio(self, body):
        return self.sigma / body.radius

    def path_radius(self, body):
        return self.sigma

    def generalized_mass(self, body):
        return body.kappa * body.mass * self.sigma**2


@dataclass
class PathResult:
    """What a run on a path track produced."""

    scene: PathScene
    status: Status
    message: str
    t_final: float
    state: np.ndarray
    collisions: list = field(default_factory=list)
    limiter_impacts: list = field(default_factory=list)
    junctions: list = field(default_factory=list)
    energy_initial: float = 0.0
    energy_final: float = 0.0
    n_steps: int = 0
    wall_time: float = 0.0
    branches: list = field(default_factory=list)
    inconsistent: int = 0
    #: first time each body's normal force fell to zero on a two-sided track
    warnings: list = field(default_factory=list)

    @property
    def n_collisions(self) -> int:
        return len(self.collisions)

    def collision_array(self) -> np.ndarray:
        return np.array([[row[c] for c in COLLISION_COLUMNS] for row in self.collisions], dtype=float).reshape(
            -1, len(COLLISION_COLUMNS))

    def sample(self, n_points: int = 2000):
        """(t, state) on a uniform grid over the run, from the integrator's dense output."""
        if not self.branches:
            raise ValueError("run with keep_branches=True to sample the trajectory")
        t = np.linspace(0.0, self.t_final, n_points)
        out = np.empty((n_points, 2 * len(self.scene.bodies)))
        # a branch is [t0, t1) of one propagate call; branch k owns its interval
        starts = np.array([b[0] for b in self.branches])
        idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(self.branches) - 1)
        for k, (t0, t1, c_out, jumps) in enumerate(self.branches):
            sel = idx == k
            if np.any(sel):
                out[sel] = c_out(np.clip(t[sel], t0, t1))
        return t, out

    def summary(self) -> dict:
        return {
            "scene": self.scene.name, "status": self.status.value, "message": self.message,
            "t_final": self.t_final, "collisions": self.n_collisions,
            "limiter_impacts": len(self.limiter_impacts), "junction_crossings": len(self.junctions),
            "inconsistent_collisions": self.inconsistent, "warnings": self.warnings,
            "first_integral_initial": self.energy_initial, "first_integral_final": self.energy_final,
            "steps": self.n_steps, "wall_time_s": self.wall_time,
        }


def body_energy(scene: PathScene, n: int, q, v):
    """Jacobi first integral of body n in the rotating plane (paper eq. 92, any body):

    H = 1/2 kappa m F q'^2 - 1/2 m Omega^2 (x_C - a)^2 + m g y_C,
    the body's moment about the vertical axis left out (a constant).
    """
    body = scene.bodies[n]
    kappa, m = float(body.kappa), float(body.mass)
    x_c, y_c = scene.centre(n, q)
    F = speed_factor(scene, n, q) ** 2
    om2 = float(scene.frame.omega) ** 2
    return 0.5 * kappa * m * F * v * v - 0.5 * m * om2 * (x_c - float(scene.frame.axis_x)) ** 2 + m * float(scene.g) * y_c


def total_energy(scene: PathScene, state) -> float:
    state = np.asarray(state, dtype=float)
    return float(sum(body_energy(scene, n, state[2 * n], state[2 * n + 1]) for n in range(len(scene.bodies))))


def speed_factor(scene: PathScene, n: int, q):
    """|dC/dq|: 1 on an arc chain (q is arc length), sqrt(F) on a curve (eq. 94)."""
    if isinstance(scene.track, CurveTrack):
        return np.sqrt(scene.track.metric(np.asarray(q, dtype=float), float(scene.bodies[n].radius)))
    return np.ones_like(np.asarray(q, dtype=float))


def centre_velocity_direction(scene: PathScene, n: int, q: float) -> np.ndarray:
    """dC/dq of body n at q (a 2-vector)."""
    if isinstance(scene.track, CurveTrack):
        track, r = scene.track, float(scene.bodies[n].radius)
        d1 = float(track.numeric(track.df, q))
        d2 = float(track.numeric(track.d2f, q))
        one = 1 - r * d2 / (1 + d1 * d1) ** 1.5
        return np.array([one, d1 * one])
    pieces = scene.track.pieces(scene.bodies[n])
    a = pieces[int(piece_index(pieces, q))].alpha(q)
    return np.array([np.cos(a), np.sin(a)])


def time_scale(scene: PathScene) -> float:
    """sqrt(size / g): the scale on which accumulation is judged."""
    lo, hi = scene.domain(0)
    return float(np.sqrt(max(hi - lo, 1e-300) / float(scene.g)))


def simulate_path(scene: PathScene, *, t_end: float | None = None, max_collisions: int | None = None,
                  keep_branches: bool = False, tol: float | None = None, precision: str = "long") -> PathResult:
    """Integrate ``scene`` to t_end (or max_collisions), resolving every event.

    ``precision``: ``long`` (x87 extended, the default: the first integral
    holds to ~1e-16 over long runs) or ``double`` (about 3x faster).
    """
    if precision not in FLOAT_TYPES:
        raise ValueError(f"precision: must be one of {' | '.join(FLOAT_TYPES)}, got {precision!r}")
    fp_type = FLOAT_TYPES[precision]
    started = time.perf_counter()
    t_end = float(scene.run.t_end if t_end is None else t_end)
    max_collisions = scene.run.max_collisions if max_collisions is None else max_collisions
    system = PathSystem(scene, fp_type)
    n = system.n
    pieces = [int(piece_index(system.pieces[b], float(scene.q[b]))) for b in range(n)] if system.chain else []
    state = np.array([to_float(v, fp_type) for b in range(n) for v in (scene.q[b], scene.dq[b])], dtype=fp_type)
    fired: list[int] = []
    options = {"fp_type": fp_type} if tol is None else {"fp_type": fp_type, "tol": fp_type(tol)}
    scale = time_scale(scene)
    # one ulp of the motion's time scale (as on the circle: a cooldown of 0 loses collisions)
    cooldown = float(np.finfo(fp_type).eps) * scale
    ta = hy.taylor_adaptive(system.equations, state, t_events=system.events(fired, cooldown), **options)
    # heyoka holds the parameters up to the highest one the equations use
    parameters = np.array(system.initial_parameters(pieces), dtype=fp_type)
    ta.pars[:] = parameters[:len(ta.pars)]
    result = PathResult(scene=scene, status=Status.COMPLETED, message="", t_final=0.0, state=np.array(state))
    result.energy_initial = total_energy(scene, state)
    k_law = float(scene.law.restitution)
    k_lim = float(scene.limiter_restitution)
    last: dict = {}
    status, message = Status.COMPLETED, f"reached t_end = {t_end:.17g} s"
    warned: set = set()
    fn = system.centre_function
    start = fn(np.asarray(ta.state), pars=np.asarray(parameters[:fn.nparams]))
    for b in range(n):
        if start[4 * b + 3] < 0:
            left = _leaves(scene, b, 0.0, float(state[2 * b]))
            if scene.track_sides == "one":
                status, message = Status.LEFT_TRACK, left + " (at the start)"
            else:
                result.warnings.append(left + " (at the start; the two-sided track holds it)")
                warned.add(b)
    while status is Status.COMPLETED:
        fired.clear()
        t0 = float(ta.time)
        out = ta.propagate_until(fp_type(t_end), c_output=keep_branches)
        result.n_steps += int(out[3])
        if keep_branches:
            result.branches.append((t0, float(ta.time), out[4], None))
        if out[0] == hy.taylor_outcome.time_limit:
            break
        if not fired:
            status, message = Status.FAILED, f"integration stopped at t = {float(ta.time):.17g} s: {out[0]}"
            break
        overlap = _overlap(scene, ta.state)
        if overlap:
            status, message = Status.OVERLAP, f"at t = {float(ta.time):.17g} s " + overlap
            break
        ev = system.event_specs[fired[0]]
        t = float(ta.time)
        key = (ev.kind, ev.body)
        prev_t, prev_dt, repeats = last.get(key, (-np.inf, np.inf, 0))
        dt = t - prev_t
        repeats = repeats + 1 if dt < ZENO_INTERVAL * scale else 0
        last[key] = (t, dt, repeats)
        # an accumulating sequence: intervals shrinking by rho < 1 end within the
        # sum of the remaining geometric series, dt rho / (1 - rho)
        rho = dt / prev_dt if 0 < prev_dt < np.inf else np.inf
        remaining = dt * rho / (1 - rho) if rho < ZENO_RATIO else np.inf
        if ev.kind in ("gap", "lower", "upper") and (repeats >= ZENO_REPEATS or remaining < ZENO_REMAINING * scale):
            what = f"bodies {ev.body + 1} and {ev.body + 2}" if ev.kind == "gap" else f"body {ev.body + 1} at a limiter"
            status = Status.CONTACT
            message = (f"impacts of {what} accumulate at t = {t + remaining if np.isfinite(remaining) else t:.17g} s "
                       f"(intervals shrink by {rho:.3g}; the rest of the series lasts {remaining:.3g} s): "
                       "persistent contact, which is not modelled on arc-chain and curve tracks yet")
            break
        s = ta.state
        if ev.kind == "normal":
            if scene.track_sides == "one":
                status, message = Status.LEFT_TRACK, _leaves(scene, ev.body, t, float(s[2 * ev.body]))
                break
            if ev.body not in warned:
                warned.add(ev.body)
                result.warnings.append(_leaves(scene, ev.body, t, float(s[2 * ev.body]))
                                       + "; the two-sided track holds it (sides = \"one\" stops here)")
            continue
        if ev.kind == "gap":
            ok, msg, closing, opening = _collide(scene, ta, ev.body, k_law, result)
            if not ok:
                status, message = Status.INCONSISTENT, msg
                break
            _off_event_surfaces(system, ta, parameters)
            slow = abs(closing) < SLOW_APPROACH * float(scene.g) * scale
            if (opening <= SEPARATION * abs(closing) or slow) and _recloses(scene, ta, ev.body, scale):
                status = Status.CONTACT
                message = (f"bodies {ev.body + 1} and {ev.body + 2} stay in contact after collision "
                           f"{result.n_collisions} at t = {t:.17g} s (they leave it at a gap rate "
                           f"{opening:.3g} m/s and are pressed together); contact modes are not modelled "
                           "on arc-chain and curve tracks yet")
                break
            if max_collisions is not None and result.n_collisions >= max_collisions:
                status, message = Status.MAX_COLLISIONS, f"stopped after max_collisions = {max_collisions}"
                break
            continue
        b = ev.body
        if system.chain:
            k_piece = pieces[b]
            step = 1 if ev.kind == "upper" else -1
            if 0 <= k_piece + step < len(system.pieces[b]):
                pieces[b] = k_piece + step
                base = system.par_index(b, "lo")
                values = system.piece_values(b, pieces[b])
                parameters[base:base + len(values)] = values
                ta.pars[:] = parameters[:len(ta.pars)]
                result.junctions.append({"t": t, "body": b + 1, "from": k_piece + 1, "to": pieces[b] + 1,
                                         "q": float(s[2 * b])})
                _off_event_surfaces(system, ta, parameters)
                continue
        v = float(s[2 * b + 1])
        s[2 * b + 1] = -k_lim * v
        result.limiter_impacts.append({"t": t, "body": b + 1, "end": ev.kind, "q": float(s[2 * b]),
                                       "v_before": v, "v_after": float(s[2 * b + 1])})
        _off_event_surfaces(system, ta, parameters)
        if abs(float(s[2 * b + 1])) < SLOW_APPROACH * float(scene.g) * scale and _rests_on_limiter(
                scene, ta, b, ev.kind, scale):
            status = Status.CONTACT
            message = (f"body {b + 1} comes to rest against the {ev.kind} limiter at t = {t:.17g} s "
                       f"(it rebounds at {abs(float(s[2 * b + 1])):.3g} m/s and is pressed back); resting "
                       "contact is not modelled on arc-chain and curve tracks yet")
            break
    overlap = _overlap(scene, ta.state)
    if overlap and status is not Status.OVERLAP:
        # never report success over an overlap
        status, message = Status.OVERLAP, f"at the end (t = {float(ta.time):.17g} s) " + overlap
    result.status, result.message = status, message
    result.t_final = float(ta.time)
    result.state = np.array(ta.state, dtype=float)
    result.energy_final = total_energy(scene, result.state)
    result.wall_time = time.perf_counter() - started
    return result


def _overlap(scene: PathScene, state) -> str:
    """'' or a message naming the first pair deeper than OVERLAP_TOLERANCE."""
    state = np.asarray(state, dtype=float)
    for i in range(len(scene.bodies) - 1):
        gap = float(scene.gap(i, state[2 * i], state[2 * i + 2]))
        if gap < -OVERLAP_TOLERANCE:
            return f"bodies {i + 1} and {i + 2} overlap by {-gap:.3g} m (a collision was missed)"
    return ""


def _recloses(scene: PathScene, ta, i: int, scale: float) -> bool:
    """Do bodies i, i+1, touching and not separating, press into each other?

    Integrates a copy of the integrator for a short while (1e-4 of the
    motion's time scale): the gap then is ~1/2 G'' dt^2, negative when the
    bodies are pressed together; heyoka cannot see that crossing (the gap
    starts at 0 and never changes sign within a step).
    """
    x = _probe(ta, scale)
    # not separated by more than the size of a rounding error of the positions
    return float(scene.gap(i, x[2 * i], x[2 * i + 2])) <= 1e-12


def _rests_on_limiter(scene: PathScene, ta, b: int, end: str, scale: float) -> bool:
    """Is body b, just rebounding slowly from a limiter, pressed back onto it? (probe as in _recloses)"""
    q = float(_probe(ta, scale)[2 * b])
    lo, hi = scene.domain(b)
    return (q - lo if end == "lower" else hi - q) <= 1e-12


def _probe(ta, scale: float) -> np.ndarray:
    """The state after integrating a copy of ``ta`` for 1e-4 of the motion's time scale.

    A terminal event may stop the copy earlier; the callers read the positions
    where it stopped (a re-hit leaves them on the surface: pressed back).
    """
    probe = copy.deepcopy(ta)
    probe.propagate_for(np.asarray(probe.time).dtype.type(1e-4 * scale))
    return np.asarray(probe.state, dtype=float)


def _leaves(scene: PathScene, b: int, t: float, q: float) -> str:
    x_c, y_c = scene.centre(b, q)
    return (f"body {b + 1} would leave the track at t = {t:.17g} s, {scene.coordinate} = {q:.17g} "
            f"(centre at x = {float(x_c):.6g} m, y = {float(y_c):.6g} m): the normal force reaches 0")


def _off_event_surfaces(system: PathSystem, ta, parameters) -> None:
    """Move off any event surface the state sits on exactly.

    heyoka misses a root in the step that starts with an event function
    exactly 0.0 (measured: x(0) = 0, x' = -0.01, x'' = 5 never fires on the
    way back up; +-1e-16 does). After a junction, a limiter or a collision
    the state often sits exactly on a surface; one ulp of the body's
    coordinate into the allowed side fixes it and moves the energy by
    ~1e-16 of its scale. On an arc chain the piece's bound moves instead
    (the piece formulas hold a few ulp beyond their ends to O(ulp)).
    """
    for _ in range(4):
        fn = system.event_function
        values = fn(np.asarray(ta.state), pars=np.asarray(parameters[:fn.nparams]))
        zero = [n for n in np.flatnonzero(values == 0.0) if system.event_specs[n].kind != "normal"]
        if not zero:
            return
        for n in zero:
            ev = system.event_specs[n]
            if ev.kind == "normal":
                continue  # a warning surface: nothing to protect
            if system.chain and ev.kind in ("lower", "upper"):
                k = system.par_index(ev.body, "lo" if ev.kind == "lower" else "hi")
                parameters[k] = np.nextafter(parameters[k], -np.inf if ev.kind == "lower" else np.inf)
                ta.pars[:] = parameters[:len(ta.pars)]
                continue
            s = ta.state
            if ev.kind == "gap":
                j = 2 * (ev.body + 1)  # the right body steps forward
                s[j] = np.nextafter(s[j], np.inf)
            else:
                k = 2 * ev.body
                s[k] = np.nextafter(s[k], np.inf if ev.kind == "lower" else -np.inf)


def _collide(scene: PathScene, ta, i: int, k: float, result: PathResult) -> tuple[bool, str, float, float]:
    """Resolve the collision of bodies i and i+1 in place: (ok, message to stop, gap rate before, after)."""
    s = ta.state
    j = i + 1
    qi, vi, qj, vj = (float(x) for x in (s[2 * i], s[2 * i + 1], s[2 * j], s[2 * j + 1]))
    bi, bj = scene.bodies[i], scene.bodies[j]
    ci, cj = scene.centre(i, qi), scene.centre(j, qj)
    e = np.array([float(cj[0] - ci[0]), float(cj[1] - ci[1])])
    e /= np.hypot(*e)
    # gap rate dG/dt = g_i v_i + g_j v_j with the gradient of the centre distance
    g_i = -float(e @ centre_velocity_direction(scene, i, qi))
    g_j = float(e @ centre_velocity_direction(scene, j, qj))
    closing = g_i * vi + g_j * vj
    sig_i, sig_j = float(speed_factor(scene, i, qi)), float(speed_factor(scene, j, qj))
    law_i = scene.law.variables(LocalMetric(sig_i), bi)
    law_j = scene.law.variables(LocalMetric(sig_j), bj)
    c_i, c_j = float(law_i.scale), float(law_j.scale)
    M_i, M_j = float(law_i.inertia), float(law_j.inertia)
    u_i, u_j = c_i * vi, c_j * vj
    du = u_i - u_j
    # paper eqs. (10)-(11) in the law's variables
    vi_new = (u_i - (1 + k) * M_j / (M_i + M_j) * du) / c_i
    vj_new = (u_j + (1 + k) * M_i / (M_i + M_j) * du) / c_j
    flag = 0
    opening = g_i * vi_new + g_j * vj_new
    if opening < -CONSISTENCY_TOLERANCE * abs(closing) or closing >= 0:
        result.inconsistent += 1
        if scene.on_inconsistent == "error":
            return False, (f"collision {result.n_collisions + 1} of bodies {i + 1} and {j + 1} at "
                           f"t = {float(ta.time):.17g} s: the {scene.law.name} law leaves them approaching "
                           f"(gap rate {opening:.3g} m/s after, {closing:.3g} before); policy 'error'"), closing, opening
        # Newton's law on the gap rate with the generalized masses kappa m sigma^2
        Gi, Gj = float(bi.kappa * bi.mass) * sig_i**2, float(bj.kappa * bj.mass) * sig_j**2
        P = -(1 + k) * closing / (g_i * g_i / Gi + g_j * g_j / Gj)
        vi_new, vj_new = vi + P * g_i / Gi, vj + P * g_j / Gj
        flag = 1
    before = float(body_energy(scene, i, qi, vi) + body_energy(scene, j, qj, vj))
    s[2 * i + 1], s[2 * j + 1] = vi_new, vj_new
    after = float(body_energy(scene, i, qi, vi_new) + body_energy(scene, j, qj, vj_new))
    roll_i = sig_i / float(bi.radius) if bi.radius else np.nan
    roll_j = sig_j / float(bj.radius) if bj.radius else np.nan
    result.collisions.append({
        "n": result.n_collisions + 1, "t": float(ta.time), "i": i + 1, "j": j + 1, "q_i": qi, "q_j": qj,
        "v_i_before": vi, "v_j_before": vj, "v_i_after": vi_new, "v_j_after": vj_new,
        "omega_i_before": roll_i * vi, "omega_j_before": roll_j * vj,
        "omega_i_after": roll_i * vi_new, "omega_j_after": roll_j * vj_new,
        "energy_before": before, "energy_after": after, "law_flag": flag,
    })
    return True, "", closing, g_i * vi_new + g_j * vj_new
