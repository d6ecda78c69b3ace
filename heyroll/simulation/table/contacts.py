"""Contacts of a table scene in the run's own numbers: distances, normals, who approaches.

Detection is heyoka's (events); this module judges the state at an event:
which other contacts touch at the same instant (to be resolved with the one
that fired), and whether anything overlaps (a missed impact).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...model._numbers import workprec
from ...model.table import TableScene
from ...model.table.boundaries import sqrt
from ..precision import Precision
from .system import STATE_PER_BALL, TableSystem, _extent


#: Pairs and walls from which a double run checks its contacts with numpy (one pass) rather than one by one.
VECTOR_CONTACTS = 24
#: Within this distance (relative to the table's size) from its cushion a finite ball in an ellipse is placed by
#: the exact distance, not the gap polynomial's first order: near the nearly cusped ends of the centre's curve
#: (R near b^2/a) that polynomial's round-off moved the cushion by 3.5e-8 m (an impact at the exact contact
#: was then reported as an overlap, review).
EXACT_BAND = 2.0**-16


@dataclass(frozen=True)
class Contact:
    """A touching contact: ``kind`` wall | pair; ball ``i``; ``j`` the other ball (pair) or the wall;
    ``normal`` from i to j (pair) or out of the table (wall); ``distance`` (< 0: overlap)."""

    kind: str
    i: int
    j: int
    normal: tuple
    distance: object


def ball_state(state, k) -> tuple:
    """(x, y, vx, vy, ux, uy) of ball k."""
    return tuple(state[STATE_PER_BALL * k:STATE_PER_BALL * (k + 1)])


class ContactGeometry:
    def __init__(self, scene: TableScene, system: TableSystem, precision: Precision):
        self.scene, self.system = scene, system
        self.boundary = scene.boundary
        num = precision.number
        size = max(abs(float(v)) for v in _extent(scene.boundary))
        self.size = num(size)
        #: a contact "touches" within this distance: the event's root is exact to a few ulps; a
        #: symmetric start brings several contacts to the same instant up to round-off
        self.touch = num(2.0**12 * precision.epsilon * size)
        #: beyond this a contact overlaps: an impact was missed
        self.overlap = num(2.0**20 * precision.epsilon * size)
        self.zero = num(0)
        self.vector = None
        #: Newton's method on the foot point stops one step after a relative step this small
        self.newton_tol = num(2.0**-((precision.bits + 1) // 2))
        #: balls whose cushion impacts are polished with the boundary's exact distance (ellipse, R > 0)
        self.exact = {}
        #: (1/a^2, 1/b^2) of an ellipse: a centre on or past it overlaps whatever its gap polynomial says
        self.conic = None
        if scene.boundary.kind == "ellipse":
            with workprec():
                self.conic = (num(1 / scene.boundary.a**2), num(1 / scene.boundary.b**2))
        if hasattr(self.boundary, "exact_distance"):
            for k, ball in enumerate(scene.balls):
                if not self.boundary.conic(ball.body.radius):
                    with workprec():  # a^2 at the model's precision (mpmath's global 53 bits broke quad runs)
                        a2, b2 = self.boundary.a ** 2, self.boundary.b ** 2
                    self.exact[k] = (num(a2), num(b2), num(ball.body.radius))
        self.vector = self._vectorized(precision)

    def wall(self, k, w, x, y) -> tuple:
        """(distance, outward unit normal) of ball k's centre from wall w (first order: g/|grad g|)."""
        _, c = self.system.walls[(k, w)]
        if self.conic is not None and len(c) > 2 and x * x * self.conic[0] + y * y * self.conic[1] >= 1:
            return -self.size, self._outward(x, y)  # past the cushion itself: an overlap of at least R
        g = self.boundary.gap(w, x, y, c)
        gx, gy = self.boundary.gradient(w, x, y, c)
        norm = sqrt(gx * gx + gy * gy)
        if not norm > self.zero:  # the centre of a circular table: as far from the cushion as can be
            return -g, (self.zero, self.zero)
        if k in self.exact and abs(g / norm) < EXACT_BAND * self.size:
            found = self.exact_wall(k, x, y)
            if found is not None:
                return found[0], found[1]
        return -g / norm, (gx / norm, gy / norm)

    def _outward(self, x, y):
        gx, gy = x * self.conic[0], y * self.conic[1]
        norm = sqrt(gx * gx + gy * gy)
        return gx / norm, gy / norm

    def exact_wall(self, k, x, y):
        """(distance from the cushion minus R, outward unit normal) of ball k by the exact distance, or None."""
        a2, b2, r = self.exact[k]
        # Newton's method starts from the foot point guessed one radius along the normal at the centre
        gx, gy = x / a2, y / b2
        g = sqrt(gx * gx + gy * gy)
        fx, fy = (x + r * gx / g) / a2, (y + r * gy / g) / b2
        found = self.boundary.exact_distance(x, y, a2, b2, self.zero, -r / sqrt(fx * fx + fy * fy), self.newton_tol)
        if found is None:
            return None
        d, normal = found
        return d - r, normal

    def pair(self, i, j, state) -> tuple:
        """(distance, unit normal from i to j) of balls i < j."""
        xi, yi = state[STATE_PER_BALL * i], state[STATE_PER_BALL * i + 1]
        xj, yj = state[STATE_PER_BALL * j], state[STATE_PER_BALL * j + 1]
        dx, dy = xj - xi, yj - yi
        d = sqrt(dx * dx + dy * dy)
        _, reach = self.system.pairs[(i, j)]
        if not d > self.zero:  # one centre: no direction (two balls that far overlap are reported, any normal)
            return d - reach, (self.zero + 1, self.zero)
        return d - reach, (dx / d, dy / d)

    def contacts(self, state, within) -> list:
        """Every contact closer than ``within`` (pairs first, in scene order, then walls by ball)."""
        if self.vector is not None:
            return self._contacts_float64(state, within)
        out = []
        n = self.system.n_balls
        for i in range(n):
            for j in range(i + 1, n):
                d, nrm = self.pair(i, j, state)
                if d <= within and not (d == self.zero and not self.system.pairs[(i, j)][1] > self.zero):
                    out.append(Contact("pair", i, j, nrm, d))  # (two particles at one point do not meet)
        for (k, w) in self.system.walls:
            d, nrm = self.wall(k, w, state[STATE_PER_BALL * k], state[STATE_PER_BALL * k + 1])
            if d <= within:
                out.append(Contact("wall", k, w, nrm, d))
        return out

    def _vectorized(self, precision: Precision):
        """Arrays for :meth:`_contacts_float64` (double runs: one numpy pass over all pairs and walls)."""
        n = self.system.n_balls
        if precision.name != "double" or n * (n - 1) // 2 + len(self.system.walls) < VECTOR_CONTACTS:
            return None
        first, second = np.triu_indices(n, 1)
        reach = np.array([float(self.system.pairs[(int(i), int(j))][1]) for i, j in zip(first, second)])
        walls = {}
        for (k, w), (_, values) in self.system.walls.items():
            walls.setdefault(w, []).append((k, [float(v) for v in values]))
        if hasattr(self.boundary, "vertices"):  # straight walls: distance = h_e - R - n_e . c, one matrix
            normals = np.array([[walls[w][0][1][0], walls[w][0][1][1]] for w in sorted(walls)])
            offsets = np.empty((n, len(walls)))
            for w in sorted(walls):
                for k, c in walls[w]:
                    offsets[k, w] = c[2]
            return first, second, reach, ("straight", normals, offsets)
        per_wall = {}
        for w, entries in walls.items():
            if len({len(c) for _, c in entries}) != 1:  # mixed particles and balls (ellipse): per length
                return None
            balls = np.array([k for k, _ in entries])
            constants = [np.array([c[m] for _, c in entries]) for m in range(len(entries[0][1]))]
            per_wall[w] = (balls, constants)
        return first, second, reach, per_wall

    def _contacts_float64(self, state, within) -> list:
        first, second, reach, per_wall = self.vector
        s = np.asarray(state, dtype=float).reshape(-1, STATE_PER_BALL)
        out = []
        if len(first):
            dx, dy = s[second, 0] - s[first, 0], s[second, 1] - s[first, 1]
            d = np.hypot(dx, dy)
            distance = d - reach
            for m in np.flatnonzero(distance <= within):
                if d[m] == 0:  # one centre: two particles do not meet; two balls that far overlap, any normal
                    if reach[m] > 0:
                        out.append(Contact("pair", int(first[m]), int(second[m]), (1.0, 0.0), distance[m]))
                    continue
                out.append(Contact("pair", int(first[m]), int(second[m]), (dx[m] / d[m], dy[m] / d[m]),
                                   distance[m]))
        walls = []
        if isinstance(per_wall, tuple):  # straight walls
            _, normals, offsets = per_wall
            distance = offsets - s[:, 0:1] * normals[:, 0] - s[:, 1:2] * normals[:, 1]
            for k, w in zip(*np.nonzero(distance <= within)):
                walls.append(Contact("wall", int(k), int(w), (normals[w, 0], normals[w, 1]), distance[k, w]))
            return out + walls
        for w, (balls, constants) in per_wall.items():
            x, y = s[balls, 0], s[balls, 1]
            g = self.boundary.gap(w, x, y, constants)
            gx, gy = self.boundary.gradient(w, x, y, constants)
            gx, gy = np.broadcast_to(gx, g.shape), np.broadcast_to(gy, g.shape)
            norm = np.hypot(gx, gy)
            with np.errstate(divide="ignore", invalid="ignore"):
                distance = np.where(norm > 0, -g / norm, np.inf)
            if self.conic is not None and len(constants) > 2:  # a finite ball past the ellipse itself: overlapping
                distance = np.where(x * x * float(self.conic[0]) + y * y * float(self.conic[1]) >= 1,
                                    -float(self.size), distance)
            band = within + (EXACT_BAND * float(self.size) if self.exact else 0.0)
            for m in np.flatnonzero(distance <= band):
                k = int(balls[m])
                if k in self.exact:  # placed by the exact distance (EXACT_BAND)
                    d, normal = self.wall(k, w, float(x[m]), float(y[m]))
                    if d <= within:
                        walls.append(Contact("wall", k, w, normal, d))
                elif distance[m] <= within:
                    walls.append(Contact("wall", k, w, (gx[m] / norm[m], gy[m] / norm[m]), distance[m]))
        walls.sort(key=lambda c: (c.i, c.j))
        return out + walls

    def approach(self, contact: Contact, state):
        """Closing speed of a contact (> 0: approaching)."""
        vi = state[STATE_PER_BALL * contact.i + 2], state[STATE_PER_BALL * contact.i + 3]
        nx, ny = contact.normal
        if contact.kind == "wall":
            return vi[0] * nx + vi[1] * ny
        vj = state[STATE_PER_BALL * contact.j + 2], state[STATE_PER_BALL * contact.j + 3]
        return (vi[0] - vj[0]) * nx + (vi[1] - vj[1]) * ny
