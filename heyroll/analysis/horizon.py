"""How far can a run be trusted? Double vs quad collision sequences, and the largest Lyapunov exponent.

* :func:`predictability_horizon` runs a scene in double and in quad precision
  with the heyroll engine and counts the leading collisions on which the two
  agree (same pair, collision times within a relative threshold). Beyond
  that collision the double run is no longer a faithful account of the
  scene: either rounding has been amplified by the dynamics (chaos) or, in a
  regular scene, the slow (linear in t) drift has reached the threshold.
* :func:`lyapunov_estimate` measures the amplification rate itself.

Both use only :func:`heyroll.simulate` and :meth:`heyroll.Scene.make`.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import mpmath
import numpy as np

from ..model.scene import RunSettings, Scene

__all__ = ["HorizonResult", "LyapunovEstimate", "lyapunov_estimate", "predictability_horizon"]


def _to_mpf(x):
    """An engine number (float, heyoka real128 or real) as an mpf without losing digits."""
    if isinstance(x, (float, int, np.floating, np.integer)):
        return mpmath.mpf(float(x))
    return mpmath.mpf(str(x))


# ----------------------------------------------------------------------------- predictability horizon


@dataclass(frozen=True)
class HorizonResult:
    """Double vs quad on one scene, collision by collision.

    ``rel_diff[n]`` = |t_double - t_quad| / |t_quad| of collision n + 1 (over
    the collisions both runs have; computed in mpmath from the quad value's
    full digits). ``same_pair[n]``: both runs have the same pair there.
    ``n_agree`` is the number of leading collisions with the same pair and
    ``rel_diff <= threshold``; ``first_disagreement`` is the 1-based number of
    the first collision that does not agree (None if all compared collisions
    agree), ``t_horizon`` the (quad) time of the last agreeing collision.
    Wall times are of the integration (each precision's code is compiled by
    a warm-up call first, unless ``warm_up=False``).
    """

    threshold: float
    rel_diff: np.ndarray
    same_pair: np.ndarray
    n_agree: int
    first_disagreement: int | None
    t_horizon: float
    n_double: int
    n_quad: int
    status_double: str
    status_quad: str
    wall_time_double: float
    wall_time_quad: float
    message: str

    @property
    def n_compared(self) -> int:
        return int(self.rel_diff.size)

    @property
    def all_agree(self) -> bool:
        return self.first_disagreement is None


def predictability_horizon(
    scene: Scene,
    n_max: int = 200,
    threshold: float = 1e-10,
    *,
    t_end=None,
    high_accuracy: bool = False,
    warm_up: bool = True,
) -> HorizonResult:
    """Count how many leading collisions a double run gets right, taking a quad run as the truth.

    Both runs stop after ``n_max`` collisions or at ``t_end`` (default: the
    scene's); the quad run also four motion time scales past the double run's
    last collision (nothing is compared beyond it). A collision agrees when both runs collide the same pair and
    |t_double - t_quad| <= threshold |t_quad|; counting stops at the first
    one that does not (after a different pair the sequences are unrelated).
    """
    import heyroll

    if n_max < 1:
        raise ValueError("n_max must be >= 1")
    if not threshold > 0:
        raise ValueError("threshold must be > 0")
    from ..simulation.driver import motion_time_scale

    t_end = scene.run.t_end if t_end is None else t_end
    runs = {}
    for precision in ("double", "quad"):
        if precision == "quad":
            # The quad run (~100x the cost per step) matters only up to the double run's last collision: past it
            # (persistent contact, a body alone) there is nothing to compare. To t_end = 1e5 s it took minutes
            # (validate on a dissipative scene: acceptance test); a few time scales past that collision suffice.
            rd = runs["double"][0]
            last = float(rd.times[-1]) if rd.times.size else 0.0
            t_end = min(float(t_end), last * (1 + 1e-9) + 4 * motion_time_scale(scene))
        if warm_up:  # builds (JIT-compiles) the integrator: a run to the first collision
            heyroll.simulate(scene, t_end=t_end, max_collisions=1, precision=precision)
        started = time.perf_counter()
        result = heyroll.simulate(
            scene, t_end=t_end, max_collisions=n_max, precision=precision, high_accuracy=high_accuracy
        )
        runs[precision] = (result, time.perf_counter() - started)
    (rd, wd), (rq, wq) = runs["double"], runs["quad"]
    n = min(rd.n_collisions, rq.n_collisions)
    with mpmath.workdps(40):
        rel = np.array(
            [
                float(abs(_to_mpf(rd.times[k]) - _to_mpf(rq.times[k])) / abs(_to_mpf(rq.times[k])))
                for k in range(n)
            ]
        )
    same = np.asarray(rd.pair_numbers[:n]) == np.asarray(rq.pair_numbers[:n])
    good = same & (rel <= threshold)
    bad = np.flatnonzero(~good)
    n_agree = int(bad[0]) if bad.size else n
    first = n_agree + 1 if bad.size else None
    t_horizon = float(_to_mpf(rq.times[n_agree - 1])) if n_agree else 0.0
    if first is not None:
        why = "a different pair" if not same[n_agree] else f"relative difference {rel[n_agree]:.3g} in t"
        message = (
            f"double and quad agree on the first {n_agree} collisions (to {threshold:g} relative in t, "
            f"same pairs); collision {first} differs ({why})"
        )
    else:
        message = (
            f"double and quad agree on all {n} collisions compared (to {threshold:g} relative in t, same pairs); "
            f"largest relative difference {rel.max() if n else 0.0:.3g}: the horizon is beyond collision {n}"
        )
    if rd.n_collisions != rq.n_collisions:
        message += f"; the runs have {rd.n_collisions} (double) and {rq.n_collisions} (quad) collisions"
    return HorizonResult(
        threshold=float(threshold),
        rel_diff=rel,
        same_pair=same,
        n_agree=n_agree,
        first_disagreement=first,
        t_horizon=t_horizon,
        n_double=rd.n_collisions,
        n_quad=rq.n_collisions,
        status_double=rd.status.value,
        status_quad=rq.status.value,
        wall_time_double=wd,
        wall_time_quad=wq,
        message=message,
    )


# ----------------------------------------------------------------------------- Lyapunov exponent


@dataclass(frozen=True)
class LyapunovEstimate:
    """Largest Lyapunov exponent of a scene by Benettin's two-trajectory method.

    ``exponent`` (1/s) is the final running estimate; ``times`` (s) and
    ``history`` (1/s) the running estimate after each renormalisation;
    ``e_folding_time`` = 1/exponent (s; inf when the exponent is <= 0).
    ``interval`` is the renormalisation interval, ``d0`` the separation kept
    between the trajectories (scaled metric, see :func:`lyapunov_estimate`),
    ``regular_level`` = log(t)/t at the final time: what a regular (non-chaotic)
    scene's estimate decays like; ``chaotic`` is True when the exponent exceeds
    twice that (a heuristic at finite t: look at ``history`` levelling off).
    ``collisions`` the reference trajectory's collisions, ``retries`` how often a
    segment end had to be moved off a collision, ``resets`` how often the
    two trajectories had different collision sequences within a segment
    (the perturbation is then restarted and that segment not counted).
    """

    exponent: float
    times: np.ndarray
    history: np.ndarray
    e_folding_time: float
    interval: float
    d0: float
    t_end: float
    regular_level: float
    chaotic: bool
    collisions: int
    retries: int
    resets: int
    wall_time: float
    message: str


#: Scene.make keyword -> Scene attribute, for the settings a rebuilt scene must keep.
def _same_contact_at_end(rx, ry) -> bool:
    """Both segments end with the same bodies in persistent contact (k < 1: their impacts accumulated, in
    numbers that a perturbation changes, into one contact): the segment ends in one mode, comparable."""
    ends = rx.mode_changes[-1].clusters, ry.mode_changes[-1].clusters
    return bool(ends[0]) and ends[0] == ends[1]


def _scene_at(scene: Scene, state, t_end, elapsed=0) -> Scene:
    """``scene`` with a new initial state (pairs recomputed by Scene.make), restarted ``elapsed`` seconds
    into the run: a forcing's phase advances by frequency * elapsed (its clock starts again at 0); every
    other setting (friction, sides, frame, limiters) is carried over."""
    nb = len(scene.bodies)
    forcing = scene.forcing
    if forcing is not None and elapsed:
        forcing = dataclasses.replace(forcing, phase=mpmath.fmod(forcing.phase + forcing.frequency * _to_mpf(elapsed),
                                                                  2 * mpmath.pi))
    return Scene.make(
        track=scene.track,
        bodies=scene.bodies,
        q=list(state[:nb]),
        dq=list(state[nb:2 * nb]),
        law=scene.law,
        g=scene.g,
        run=RunSettings.make(t_end=t_end),
        name=scene.name,
        friction=scene.track_friction,
        on_inconsistent=scene.on_inconsistent,
        track_sides=scene.track_sides,
        frame=scene.frame,
        limiter_restitution=scene.limiter_restitution,
        static_friction=scene.static_friction,
        forcing=forcing,
        simultaneous=scene.simultaneous,
    )


def _scales(scene: Scene) -> tuple[list, float]:
    """The metric's weights (one per coordinate, then one per rate) and the default renormalisation
    interval. On a circle a_k = g/(kappa_k (R - r_k)): weights 1 and 1/a_k, the interval half the
    shortest small-oscillation period pi/sqrt(a). On a path track each body's coordinate is scaled by the
    width w of its domain and its rate by w/tau, with tau = sqrt(l/g) and l the extent of the track's
    centre line (the pendulum time of the track's size); the interval is (pi/2) tau. A turning plane's
    or a forcing's own period caps the interval at a quarter of it. (The exponent does not depend on
    the metric; the interval only has to keep d0 e^(lambda interval) small.)"""
    nb = len(scene.bodies)
    if scene.track.kind == "circle":
        a = [_to_mpf(scene.track.angular_stiffness(b, scene.g)) for b in scene.bodies]
        weights = [mpmath.mpf(1)] * nb + [1 / ak for ak in a]
        interval = float(mpmath.pi / mpmath.sqrt(max(a)))
    else:
        widths, extent = [], 0.0
        for body in scene.bodies:
            lo, hi = (float(v) for v in scene.track.domain(body))
            x, y = scene.track.centre(body, np.linspace(lo, hi, 257))
            extent = max(extent, float(np.ptp(x)), float(np.ptp(y)))
            widths.append(mpmath.mpf(hi - lo))
        tau = mpmath.sqrt(mpmath.mpf(max(extent, 1e-300)) / scene.g)
        weights = [1 / (w * w) for w in widths] + [tau * tau / (w * w) for w in widths]
        interval = float(mpmath.pi / 2 * tau)
    periods = []
    if scene.frame.rotating:
        periods.append(float(2 * mpmath.pi / abs(scene.frame.omega)))
    if scene.forcing is not None:
        periods.append(scene.forcing.period)
    return weights, min([interval, *(p / 4 for p in periods)])


def lyapunov_estimate(
    scene: Scene,
    t_end: float = 200.0,
    *,
    interval: float | None = None,
    d0: float = 1e-8,
    precision: str = "double",
    seed: int = 0,
    max_retries: int = 8,
) -> LyapunovEstimate:
    """The largest Lyapunov exponent (1/s) from two nearby trajectories with periodic renormalisation.

    Method (Benettin et al. 1980): a reference trajectory x and a perturbed
    one y = x + d0 v start together; every ``interval`` seconds both are
    integrated with :func:`heyroll.simulate` (collisions and all) from their
    current states, rebuilt as scenes with :meth:`Scene.make`; the
    separation d = |y - x| is measured at the *same* time, log(d/d0)
    accumulated and y reset to x + d0 (y - x)/d. The exponent is the
    accumulated log over the elapsed time. Distances use a scaled metric
    (``_scales``): on a circle sum_k (dphi_k^2 + (dphi'_k)^2 / a_k),
    a_k = g/(kappa_k (R - r_k)), so angles and rates weigh alike; on a path
    track the coordinates in units of their domain's width and the rates in
    those widths per pendulum time of the track's size (the exponent does not
    depend on the metric). Any track, in a fixed or a turning plane, with or
    without forcing (each segment restarts the forcing's clock with its phase
    advanced by the elapsed time); not on rough tracks (their slip state is
    not rebuilt: NotImplementedError).

    Why this rather than the divergence of double and quad collision
    sequences: that divergence is seeded by rounding at every step, not
    once, so it grows even in a regular scene (linearly, like a random walk
    plus shear) and its log-slope mixes the seeding rate with the
    amplification; here one perturbation of known size is followed and
    renormalised before it leaves the linear regime (d0 e^(lambda interval)
    stays small). Comparing the two trajectories at a common time (not at
    their k-th collisions, whose times differ by O(d0)) makes the
    measured separation include the effect of the collision map on the
    deviation (the saltation matrix) without computing it. A segment whose
    end falls between the two trajectories' versions of one collision (the
    collision counts differ) is recomputed with a slightly shorter interval.
    Segments are of one length: a last piece shorter than half an interval
    is left out (the estimate then covers a little less than ``t_end``,
    which its message gives), and a last segment shortened off a collision
    ends the estimate (a run that stops on a collision is not chased).

    A regular (integrable or quasi-periodic) scene gives an estimate that
    decays like log(t)/t (the separation grows linearly); a chaotic one
    levels off at a positive value. ``precision`` applies to both runs
    (double suffices for d0 >= 1e-9: rounding adds ~1e-16/d0 relative noise).
    """
    import heyroll

    started = time.perf_counter()
    if not t_end > 0:
        raise ValueError("t_end must be > 0")
    if not 0 < d0 < 1e-3:
        raise ValueError("d0 must be in (0, 1e-3)")
    if scene.rough:
        raise NotImplementedError("lyapunov_estimate rebuilds scenes from their coordinates and rates, not their "
                                  "slip state: not estimated on a rough track")
    nb = len(scene.bodies)
    with mpmath.workdps(40):
        weights, default_interval = _scales(scene)
        interval = float(default_interval if interval is None else interval)
        if not interval > 0:
            raise ValueError("interval must be > 0")

        def norm(delta):
            return mpmath.sqrt(mpmath.fsum(w * d * d for w, d in zip(weights, delta)))

        x = [mpmath.mpf(p) for p in scene.q] + [mpmath.mpf(v) for v in scene.dq]
        rng = np.random.default_rng(seed)
        direction = [mpmath.mpf(float(c)) for c in rng.standard_normal(2 * nb)]
        n0 = norm(direction)
        d0 = mpmath.mpf(d0)
        y = [xi + d0 * c / n0 for xi, c in zip(x, direction)]

        elapsed = 0.0
        log_sum = mpmath.mpf(0)
        times, history = [], []
        collisions = retries = resets = 0
        while elapsed < t_end * (1 - 1e-12):
            tau = min(interval, t_end - elapsed)
            # A run stopped at a collision (max_collisions) ends on it: each try at a last segment then
            # shrinks by the retries, and chasing t_end made ever shorter segments (0.09 s, 3e-3 s, 8e-5 s,
            # ...) whose stretches across that collision weighed as much as whole segments (review).
            # A last piece shorter than half an interval is left out, as the Benettin estimate's segments
            # are of one length: its stretch, over a short time, only adds noise to the rate.
            last = tau >= t_end - elapsed
            if last and history and tau < interval / 2:
                break
            for attempt in range(max_retries + 1):
                try:
                    rx = heyroll.simulate(_scene_at(scene, x, tau, elapsed), t_end=tau, max_collisions=None,
                                          precision=precision)
                    ry = heyroll.simulate(_scene_at(scene, y, tau, elapsed), t_end=tau, max_collisions=None,
                                          precision=precision)
                except ValueError:  # a state rebuilt at (a rounding inside) contact: move the segment end
                    rx = ry = None
                if rx is not None and rx.success and ry.success and (
                        rx.n_collisions == ry.n_collisions or _same_contact_at_end(rx, ry)):
                    break
                if rx is not None and not rx.success:
                    raise RuntimeError(f"the reference trajectory failed at t = {elapsed:.17g} s: {rx.message}")
                retries += 1
                tau *= 0.97
            else:
                if history:  # the estimate up to here (a last segment that ends at t_end on a collision)
                    break
                raise RuntimeError(
                    f"could not place a segment end away from a collision near t = {elapsed:.17g} s "
                    f"after {max_retries} retries"
                )
            if len(rx.final_state) != 2 * nb:
                raise NotImplementedError("lyapunov_estimate handles states [q_1..q_N, dq_1..dq_N] only")
            x1 = [_to_mpf(v) for v in rx.final_state]
            y1 = [_to_mpf(v) for v in ry.final_state]
            elapsed += tau
            collisions += rx.n_collisions
            if not np.array_equal(np.asarray(rx.pair_numbers), np.asarray(ry.pair_numbers)):
                # Different collision sequences: the perturbation is no longer infinitesimal here.
                resets += 1
                y = [xi + d0 * c / n0 for xi, c in zip(x1, direction)]
                x = x1
            else:
                delta = [b - c for b, c in zip(y1, x1)]
                d = norm(delta)
                if d == 0:
                    delta, d = [d0 * c / n0 for c in direction], d0
                log_sum += mpmath.log(d / d0)
                times.append(elapsed)
                history.append(float(log_sum / elapsed))
                x = x1
                y = [xi + d0 * c / d for xi, c in zip(x1, delta)]
            if last and attempt:  # the last segment was shortened to end off a collision: the estimate ends there
                break
    exponent = history[-1] if history else math.nan
    efold = 1.0 / exponent if exponent > 0 else math.inf
    regular_level = math.log(elapsed) / elapsed if elapsed > 1 else math.inf
    chaotic = bool(exponent > 2 * regular_level)
    message = (
        f"largest Lyapunov exponent {exponent:.4g} 1/s over t = {elapsed:.6g} s ({collisions} collisions, "
        f"{len(history)} renormalisations every {interval:.4g} s, d0 = {float(d0):.1e})"
    )
    if chaotic:
        message += f"; chaotic: e-folding time {efold:.4g} s"
    else:
        message += (
            f"; consistent with a regular scene (a zero exponent's estimate decays like log(t)/t = "
            f"{regular_level:.3g} 1/s here)"
        )
    if retries or resets:
        message += f"; {retries} segment ends moved off a collision, {resets} perturbation restarts"
    return LyapunovEstimate(
        exponent=exponent,
        times=np.asarray(times),
        history=np.asarray(history),
        e_folding_time=efold,
        interval=interval,
        d0=float(d0),
        t_end=float(elapsed),
        regular_level=regular_level,
        chaotic=chaotic,
        collisions=collisions,
        retries=retries,
        resets=resets,
        wall_time=time.perf_counter() - started,
        message=message,
    )
