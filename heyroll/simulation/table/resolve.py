"""Impacts on the table resolved by the scene's laws, in the run's own numbers.

Detection (heyoka's events, :mod:`.contacts`) is kept apart from resolution
(here): a ball-cushion impact goes to the cushion model, a ball-ball impact
to the ball law (strategies in ``heyroll.model.table.laws``), and contacts
that touch at the same instant to the scene's simultaneity policy:

* ``sequential``: pairwise, in a stated order: the contact heyoka found
  first, then every other touching contact that still approaches, ball pairs
  in scene order before cushions (by ball), again and again until none
  approaches (a Newton's cradle passes the impulse along the row).
* ``impulses``: all touching contacts at once: normal impulses L >= 0 with
  Newton's restitution on every contact's separation speed,
  sigma+ >= -k sigma- where sigma- < 0 (>= 0 where it was separating),
  complementary to L (a linear complementarity problem, solved exactly by
  its active set), in the law's variables where every ball rolls and every
  law keeps rolling; where a ball slides or a law pushes through the centre
  (``slide``), as pair() does for a sliding ball: Newton's law on the masses,
  every spin kept.
"""

from __future__ import annotations

from dataclasses import dataclass

from ...model.table import TableScene
from ...model.table.laws import after_impact, with_normal
from ...model.laws import GeneralizedNewtonLaw
from ...model.table.laws.base import NormalImpulseLaw, RestitutionLaw
from ...model.table.laws.ball_ball.newton import NewtonTableLaw
from ..events import working_map
from ..precision import Precision
from ..resolve.complementarity import complementarity, relative_tolerance
from .contacts import Contact
from .system import STATE_PER_BALL

#: law_flag: 0 the scene's law, 1 Newton's law where the scene's would leave the balls approaching
#: (Hedrih's law on unequal radii), 2 a simultaneous-impulse resolution, 3 a rolling law met a sliding ball:
#: the impulse went through the centres (Newton's law with the masses), the spins were kept, 4 the ball settled
#: onto a curved cushion (k < 1: the limit of its accumulating impacts, normal speed removed) and rides it.
SCENE_LAW, FALLBACK_LAW, SIMULTANEOUS, SLIDING_BALL, SETTLED = 0, 1, 2, 3, 4


@dataclass(frozen=True)
class _RollingMassesNewton(NormalImpulseLaw, RestitutionLaw):
    """Newton's law on the normal rates with the rolling masses kappa m: the fallback where Hedrih's law would
    leave balls of unequal radii approaching (Resolver.pair); at k = 1 it keeps the rolling energy."""

    def one_dimensional(self):
        return GeneralizedNewtonLaw(restitution=self.restitution)


def _normal_rates(law, body_i, body_j, precision: Precision):
    """``rates(vn_i, vn_j)``: the outgoing normal velocities of the pair by ``law`` in the run's arithmetic. In
    double a law with an impulse runs as the tracks' collisions do (events.working_map: the constants and the map
    in double-double, a_i + q a_j = 1 + k, rounded once): from three constants rounded apart, a_i + q a_j missed
    1 + k by a rounding, the same every impact of the pair, and Hedrih's law at k = 1 gained 0.24 ulp of energy
    per impact on average, 7e-13 over 1e5 impacts (review). In the other types its three constants are rounded
    apart: working_map's a_i = 1 + k - q a_j there takes the rounding of q a_j, which for a_i << q a_j (a heavy
    ball and a light one) broke eq. 8 by 9e-17 in long, 200 times its rounding (review). Another law (mirror):
    its own constants."""
    if isinstance(law, NormalImpulseLaw) and precision.name == "double":
        return working_map(law.impulse_map(body_i, body_j), precision).apply
    constants = law.constants(body_i, body_j, precision.number)
    return lambda vn_i, vn_j: law.normal_rates(constants, vn_i, vn_j)


class Resolver:
    def __init__(self, scene: TableScene, precision: Precision):
        num = precision.number
        self.scene = scene
        self.zero = num(0)
        #: a law's outcome approaching by less than this (relative to the speeds) is round-off, not approaching
        #: (k = 0 under Newton's law left +1e-17 m/s and was marked a fallback: review)
        self.round_off = num(2.0**8 * precision.epsilon)
        #: balls without rotational inertia (particles, kappa = 1): no spin, no slip
        self.particle = [b.body.is_particle or b.body.kappa == 1 for b in scene.balls]
        n = scene.n_bodies
        #: per pair: the law's constants; Newton's law on the masses (an impulse through the centres of sliding
        #: balls, spins kept); Newton's law on the rolling masses kappa m, rolling kept (the fallback where the law
        #: leaves the balls approaching: at k = 1 it keeps the rolling energy, as the tracks' fallback does; on
        #: the masses m it had made +43 % in one impact of a sphere on a ring, review)
        self.pair_rates, self.fallback, self.rolling_fallback = {}, {}, {}
        newton = NewtonTableLaw(restitution=scene.law.restitution)
        generalized = _RollingMassesNewton(restitution=scene.law.restitution)
        for i in range(n):
            for j in range(i + 1, n):
                bi, bj = scene.balls[i].body, scene.balls[j].body
                if scene.law.name == "hedrih" and (bi.is_particle or bj.is_particle):
                    self.pair_rates[(i, j)] = None
                else:
                    self.pair_rates[(i, j)] = _normal_rates(scene.law, bi, bj, precision)
                self.fallback[(i, j)] = _normal_rates(newton, bi, bj, precision)
                self.rolling_fallback[(i, j)] = _normal_rates(generalized, bi, bj, precision)
        self.solver_relative = relative_tolerance(precision)
        self.k_cushion = num(scene.cushion.restitution)
        self.k_law = num(scene.law.restitution)
        one_d = getattr(scene.law, "one_dimensional", None)
        #: the law's velocity scale c (u = c v_n: omega_n = v_n/R for Hedrih's law, v_n for Newton's) and
        #: inertia M of each ball (J_P or m): a law impulse L changes u by L/M, so v by L/(M c)
        self.scale, self.inertia = [], []
        #: Newton's variables (u = v_n, M = m): a simultaneous group with a sliding ball (impulses)
        self.masses = [num(ball.body.mass) for ball in scene.balls]
        self.ones = [num(1) for _ in scene.balls]
        for ball in scene.balls:
            if one_d is None or ball.body.is_particle:
                self.scale.append(num(1))
                self.inertia.append(num(ball.body.mass))
            else:
                v = one_d().variables(ball.body, 1)
                self.scale.append(num(v.scale))
                self.inertia.append(num(v.inertia))

    # -- one contact -------------------------------------------------------------------------
    def wall(self, state: list, k: int, normal) -> int:
        """Ball k hits a cushion with outward normal ``normal``: state updated in place."""
        x, y, vx, vy, ux, uy = state[STATE_PER_BALL * k:STATE_PER_BALL * (k + 1)]
        vn = vx * normal[0] + vy * normal[1]
        rolling_kept = self.scene.cushion.keeps_rolling
        v, u = after_impact((vx, vy), (ux, uy), normal, -self.k_cushion * vn, rolling_kept, self.particle[k])
        if rolling_kept and not self.particle[k] and (ux != self.zero or uy != self.zero):
            # a sliding ball: its rolling rate R omega x z = v - u is reflected as v is (the paper's model
            # reverses the normal rolling rate), so that k = 1 keeps both energies
            w = (vx - ux, vy - uy)
            wn = w[0] * normal[0] + w[1] * normal[1]
            w = with_normal(w, normal, -self.k_cushion * wn)
            u = (v[0] - w[0], v[1] - w[1])
        state[STATE_PER_BALL * k + 2:STATE_PER_BALL * (k + 1)] = [v[0], v[1], u[0], u[1]]
        return SCENE_LAW

    def pair(self, state: list, i: int, j: int, normal) -> int:
        """Balls i < j collide along ``normal`` (from i to j): state updated in place."""
        law = self.scene.law
        vi = state[STATE_PER_BALL * i + 2], state[STATE_PER_BALL * i + 3]
        vj = state[STATE_PER_BALL * j + 2], state[STATE_PER_BALL * j + 3]
        vn_i = vi[0] * normal[0] + vi[1] * normal[1]
        vn_j = vj[0] * normal[0] + vj[1] * normal[1]
        flag, keeps = SCENE_LAW, law.keeps_rolling
        rates = self.pair_rates[(i, j)]
        sliding = any(not self.particle[b] and (state[STATE_PER_BALL * b + 4] != self.zero
                                                 or state[STATE_PER_BALL * b + 5] != self.zero) for b in (i, j))
        if keeps and sliding:
            # a law of rolling bodies cannot act on a ball that slides: the impulse goes through the centres
            # (Newton's law with the masses), the spins are kept (law_flag 3, as on a rough track)
            new_i, new_j = self.fallback[(i, j)](vn_i, vn_j)
            flag, keeps = SLIDING_BALL, False
        elif rates is None:
            flag = FALLBACK_LAW
            new_i, new_j = self.rolling_fallback[(i, j)](vn_i, vn_j)
        else:
            new_i, new_j = rates(vn_i, vn_j)
            if new_i - new_j > self.round_off * (abs(vn_i) + abs(vn_j)) and vn_i - vn_j > self.zero:
                # the law leaves them approaching (Hedrih's law on unequal radii): Newton's law on kappa m instead
                flag = FALLBACK_LAW
                new_i, new_j = self.rolling_fallback[(i, j)](vn_i, vn_j)
        for k, new in ((i, new_i), (j, new_j)):
            b = STATE_PER_BALL * k
            v, u = after_impact((state[b + 2], state[b + 3]), (state[b + 4], state[b + 5]), normal, new, keeps,
                                self.particle[k])
            state[b + 2:b + 6] = [v[0], v[1], u[0], u[1]]
        return flag

    # -- simultaneous impulses ---------------------------------------------------------------
    def impulses(self, state: list, contacts: list[Contact], approach) -> list:
        """Resolve ``contacts`` at once (module docstring); returns the impulses L (run type).

        In the law's variables u = c v_n with inertias M (so that one contact alone is exactly the
        scene's law): a contact's separation rate is sigma = sum_b c_b J_cb . v_b, an impulse L along
        J_cb changes v_b by L J_cb / (M_b c_b), so sigma by L sum_b J_cb . J_db / M_b (a symmetric
        positive semi-definite matrix). A cushion acts on its ball's u with the cushion's restitution.
        """
        m = len(contacts)
        balls = {c.i for c in contacts} | {c.j for c in contacts if c.kind == "pair"}
        # A group with a sliding ball or a law that pushes through the centre (slide) is resolved as pair() does
        # a sliding ball: Newton's law on the masses, every spin kept (its energy then never grows: the LCP
        # keeps the translational energy from growing, the spins' is unchanged). Hedrih's variables there, or
        # spins turned per contact, made energy (3.0 -> 9.13 J; +1.7e-3 J at k = 1: review).
        rolling = self.scene.law.keeps_rolling and self.scene.cushion.keeps_rolling and not any(
            not self.particle[b] and (state[STATE_PER_BALL * b + 4] != self.zero
                                      or state[STATE_PER_BALL * b + 5] != self.zero) for b in balls)
        inertia = self.inertia if rolling else self.masses
        scale = self.scale if rolling else self.ones
        # J_cb: the direction in which contact c's impulse pushes ball b
        pushes = []
        for c in contacts:
            nx, ny = c.normal
            if c.kind == "wall":
                pushes.append({c.i: (-nx, -ny)})
            else:
                pushes.append({c.i: (-nx, -ny), c.j: (nx, ny)})
        a = [[self.zero] * m for _ in range(m)]
        for p in range(m):
            for q in range(m):
                total = self.zero
                for b, (jx, jy) in pushes[p].items():
                    if b in pushes[q]:
                        kx, ky = pushes[q][b]
                        total = total + (jx * kx + jy * ky) / inertia[b]
                a[p][q] = total
        rhs = []
        for c, push in zip(contacts, pushes):
            sigma = self.zero
            for b, (jx, jy) in push.items():
                base = STATE_PER_BALL * b
                sigma = sigma + scale[b] * (jx * state[base + 2] + jy * state[base + 3])
            k = self.k_cushion if c.kind == "wall" else self.k_law
            rhs.append(sigma + k * sigma if sigma < self.zero else sigma)
        impulses = complementarity(a, rhs, self.zero, self.solver_relative)
        if impulses is None:
            return None
        for c, push, lam in zip(contacts, pushes, impulses):
            if not lam > self.zero:
                continue
            for b, (jx, jy) in push.items():
                base = STATE_PER_BALL * b
                mobility = lam / (inertia[b] * scale[b])
                dvx, dvy = jx * mobility, jy * mobility
                state[base + 2] = state[base + 2] + dvx
                state[base + 3] = state[base + 3] + dvy
                if self.particle[b]:
                    state[base + 4] = state[base + 5] = self.zero
                elif not rolling:  # the spin kept: the slip takes the change of v
                    state[base + 4] = state[base + 4] + dvx
                    state[base + 5] = state[base + 5] + dvy
        return impulses
