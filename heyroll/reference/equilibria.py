"""Independent mpmath solution of the equilibrium condition on a path track.

Shares no code with the model layer (:mod:`heyroll.model`) or with
:mod:`heyroll.analysis.equilibria`, which it exists to check. It takes the
track as plain data (a dict in the form of a scene file's ``[track]`` table)
and derives everything itself, in mpmath:

* ``curve``: y = f(x) is evaluated by this module's own small evaluator
  (Python's :mod:`ast`, a whitelist of numbers, ``x``, ``+ - * / **``, unary
  minus and plus, parentheses and ``sin cos exp sqrt``); f' comes from
  mpmath's numerical differentiation of f, never from a symbolic derivative.
  The coordinate q is the contact abscissa x; the body's centre is
  (x - r f'/w, f + r/w), w = sqrt(1 + f'^2).
* ``arcs`` (and ``three_arcs``, expanded to arcs): the geometry of the
  centre's path is built here from the definitions of the segments (see
  :func:`_chain`); q is the arc length s along the centre's path, 0 at the
  chain's start.

The condition is dV/dq = 0 for the effective potential per unit mass in a
vertical plane turning at Omega about the vertical line x = a,

    V/m = g y_C - 1/2 Omega^2 (x_C - a)^2,

with the derivative taken numerically (mpmath.diff) and the roots found by
mpmath's solvers at 40 digits.
"""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass
from decimal import Decimal
from fractions import Fraction

import mpmath

DIGITS = 40

#: Functions the curve evaluator may call (mpmath's, looked up at call time).
FUNCTIONS = {"sin": mpmath.sin, "cos": mpmath.cos, "exp": mpmath.exp, "sqrt": mpmath.sqrt}

#: Keys a [track] table may hold, per type. Keys the reference does not need
#: (limiter_restitution, sides, friction) are accepted and ignored, so a scene
#: file's table can be passed as it is; any other key is a ValueError.
_IGNORED_KEYS = {"limiter_restitution", "sides", "friction"}
TRACK_KEYS = {
    "curve": {"type", "y", "x_min", "x_max"} | _IGNORED_KEYS,
    "arcs": {"type", "segments", "start_x", "start_y"} | _IGNORED_KEYS,
    "three_arcs": {"type", "radius", "hump_radius", "beta"} | _IGNORED_KEYS,
}
SEGMENT_KEYS = {"arc": {"kind", "radius", "side", "start", "end"}, "line": {"kind", "angle", "length"}}

#: Largest tangent mismatch between consecutive segments (rad).
TANGENT_TOLERANCE = mpmath.mpf("1e-12")

_DECIMAL = re.compile(r"(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")


def _num(value, what: str = "value") -> mpmath.mpf:
    """A track number as an mpf: through its decimal text, ``mpf(str(value))``.

    An mpf is taken as it is (its ``str`` would round it to the current
    mpmath precision).
    """
    if isinstance(value, bool) or not isinstance(value, (int, float, str, Decimal, Fraction, mpmath.mpf)):
        raise ValueError(f"{what} must be a number or a numeric string, got {value!r}")
    if isinstance(value, mpmath.mpf):
        return mpmath.mpf(value)
    if isinstance(value, Fraction):
        return mpmath.mpf(value.numerator) / value.denominator
    try:
        out = mpmath.mpf(str(value))
    except (ValueError, TypeError):
        raise ValueError(f"{what} must be a number or a numeric string, got {value!r}") from None
    if not mpmath.isfinite(out):
        raise ValueError(f"{what} must be finite, got {value!r}")
    return out


# ------------------------------------------------------------ curve evaluator

def compile_expression(text: str, functions=None):
    """Compile the curve text y(x) into a function of one mpmath number.

    Only numbers (decimal literals), the name ``x``, ``+ - * / **``, unary
    ``-`` (and ``+``), parentheses and calls of ``sin cos exp sqrt`` with one
    argument are allowed; anything else raises ValueError. Nothing is passed
    to ``eval``: the syntax tree is walked here. Literals are read from their
    source text, at the working precision of each evaluation.

    ``functions`` (default :data:`FUNCTIONS`) maps the four names to the
    callables used: pass versions that also take other number types (e.g.
    the truncated Taylor series of :mod:`.path_collisions`) to evaluate the
    curve on them; ``x`` may then be such a number too.
    """
    if not isinstance(text, str):
        raise ValueError(f"the curve must be a string expression in x, got {text!r}")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        raise ValueError(f"cannot parse the curve {text!r}: {exc.msg}") from None
    source = text.strip()
    table = FUNCTIONS if functions is None else functions
    if set(table) != set(FUNCTIONS):
        raise ValueError(f"functions must define exactly {', '.join(FUNCTIONS)}")
    return _compile(tree.body, source, table)


def _compile(node, source: str, functions=FUNCTIONS):
    if isinstance(node, ast.Constant):
        value = node.value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"only real numbers are allowed in the curve, got {value!r}")
        literal = ast.get_source_segment(source, node)
        if literal is None or not _DECIMAL.fullmatch(literal):
            raise ValueError(f"only decimal numbers are allowed in the curve, got {literal!r}")
        values = {}  # the literal read once per working precision (mpf numbers are immutable)

        def constant(x):
            prec = mpmath.mp.prec
            value = values.get(prec)
            if value is None:
                value = values[prec] = mpmath.mpf(literal)
            return value

        return constant
    if isinstance(node, ast.Name):
        if node.id != "x":
            raise ValueError(f"unknown name {node.id!r} in the curve; the only variable is x")
        return lambda x: x
    if isinstance(node, ast.UnaryOp):
        arg = _compile(node.operand, source, functions)
        if isinstance(node.op, ast.USub):
            return lambda x: -arg(x)
        if isinstance(node.op, ast.UAdd):
            return arg
        raise ValueError(f"operator {type(node.op).__name__} is not allowed in the curve")
    if isinstance(node, ast.BinOp):
        a, b = _compile(node.left, source, functions), _compile(node.right, source, functions)
        op = type(node.op)
        if op is ast.Add:
            return lambda x: a(x) + b(x)
        if op is ast.Sub:
            return lambda x: a(x) - b(x)
        if op is ast.Mult:
            return lambda x: a(x) * b(x)
        if op is ast.Div:
            return lambda x: a(x) / b(x)
        if op is ast.Pow:
            return lambda x: _power(a(x), b(x))
        raise ValueError(f"operator {op.__name__} is not allowed in the curve (+ - * / ** only)")
    if isinstance(node, ast.Call):
        if not isinstance(node.func, ast.Name) or node.func.id not in FUNCTIONS:
            raise ValueError(f"only calls of {', '.join(FUNCTIONS)} are allowed in the curve")
        if len(node.args) != 1 or node.keywords or isinstance(node.args[0], ast.Starred):
            raise ValueError(f"{node.func.id} takes exactly one argument")
        fn, arg = functions[node.func.id], _compile(node.args[0], source, functions)
        return lambda x: fn(arg(x))
    raise ValueError(f"{type(node).__name__} is not allowed in the curve "
                     "(numbers, x, + - * / **, parentheses, sin cos exp sqrt)")


def _power(base, exponent):
    # a whole exponent stays an exact integer power (and a negative base stays real)
    if isinstance(exponent, (int, mpmath.mpf)) and exponent == mpmath.floor(exponent) and abs(exponent) <= 64:
        return base ** int(exponent)
    return base**exponent


def _real(value, where: str):
    if not isinstance(value, mpmath.mpf):
        raise ValueError(f"the curve is not real at {where} (got {value})")
    return value


# ---------------------------------------------------------------- arc chains

@dataclass(frozen=True)
class _Piece:
    """The centre's path over one segment, s in [s0, s1]."""

    kind: str          # "concave", "convex" or "line"
    s0: mpmath.mpf
    s1: mpmath.mpf
    ox: mpmath.mpf     # arcs: the circle's centre; line: the centre's start point
    oy: mpmath.mpf
    rho: mpmath.mpf    # arcs: radius of the centre's path (R - r or R + r)
    a0: mpmath.mpf     # arcs: start angle (phi or psi); line: direction th

    def centre(self, s, sin=mpmath.sin, cos=mpmath.cos):
        """(x_C, y_C) at s; ``sin`` and ``cos`` of the angle may be replaced by versions
        that take other number types (s may then be such a number)."""
        u = s - self.s0
        if self.kind == "line":
            return self.ox + u * mpmath.cos(self.a0), self.oy + u * mpmath.sin(self.a0)
        angle = self.a0 + u / self.rho
        if self.kind == "concave":
            return self.ox + self.rho * sin(angle), self.oy - self.rho * cos(angle)
        return self.ox + self.rho * sin(angle), self.oy + self.rho * cos(angle)


def _segments(track: dict):
    """(start_x, start_y, segments) of an arcs or three_arcs table, segments as tuples
    ("arc", R, side, a0, a1) or ("line", th, L) of mpf."""
    if track["type"] == "three_arcs":
        R = _num(track["radius"], "track.radius")
        R0 = _num(track["hump_radius"], "track.hump_radius")
        b = _num(track.get("beta", 0), "track.beta")
        half = mpmath.pi / 2 - b
        segs = [("arc", R, "concave", -mpmath.pi, half),
                ("arc", R0, "convex", -half, half),
                ("arc", R, "concave", -half, mpmath.pi)]
        return -(R + R0) * mpmath.cos(b), (R + R0) * mpmath.sin(b) + R, segs
    data = track.get("segments")
    if not isinstance(data, (list, tuple)) or not data:
        raise ValueError("track.segments must be a non-empty list of tables")
    segs = []
    for n, entry in enumerate(data, start=1):
        where = f"track.segments[{n}]"
        if not isinstance(entry, dict) or entry.get("kind") not in SEGMENT_KEYS:
            raise ValueError(f"{where} must be a table with kind = arc | line, got {entry!r}")
        unknown = set(entry) - SEGMENT_KEYS[entry["kind"]]
        if unknown:
            raise ValueError(f"{where}: unknown keys {sorted(unknown)}")
        if entry["kind"] == "line":
            segs.append(("line", _num(entry["angle"], f"{where}.angle"), _num(entry["length"], f"{where}.length")))
        else:
            side = entry.get("side")
            if side not in ("concave", "convex"):
                raise ValueError(f"{where}.side must be concave or convex, got {side!r}")
            segs.append(("arc", _num(entry["radius"], f"{where}.radius"), side,
                         _num(entry["start"], f"{where}.start"), _num(entry["end"], f"{where}.end")))
    return (_num(track.get("start_x", 0), "track.start_x"), _num(track.get("start_y", 0), "track.start_y"), segs)


def _directions(seg):
    """Direction of travel (angle from +x) at the start and the end of a segment."""
    if seg[0] == "line":
        return seg[1], seg[1]
    _, _, side, a0, a1 = seg
    return (a0, a1) if side == "concave" else (-a0, -a1)


def _chain(track: dict, r) -> list[_Piece]:
    """The centre's path of a body of radius r on an arc chain, piece by piece.

    The track runs from (start_x, start_y); the body lies on the left of the
    direction of travel: centre = contact point + r * left normal.

    * concave arc R, phi from a0 to a1: O = P - R (sin a0, -cos a0), surface
      O + R (sin phi, -cos phi) (direction of travel phi), centre
      O + (R - r)(sin phi, -cos phi), path length (R - r)(a1 - a0);
    * convex arc R, psi from a0 to a1: O = P - R (sin a0, cos a0), surface
      O + R (sin psi, cos psi) (direction -psi), centre O + (R + r)(sin psi, cos psi),
      path length (R + r)(a1 - a0);
    * line th, L: surface P + u (cos th, sin th), centre that + r (-sin th, cos th),
      path length L.
    """
    px, py, segs = _segments(track)
    pieces, s = [], mpmath.mpf(0)
    for n, seg in enumerate(segs, start=1):
        if n > 1:
            before, after = _directions(segs[n - 2])[1], _directions(seg)[0]
            jump = mpmath.fmod(after - before + 3 * mpmath.pi, 2 * mpmath.pi) - mpmath.pi
            if abs(jump) > TANGENT_TOLERANCE:
                raise ValueError(f"track.segments[{n}] does not continue the tangent of segment {n - 1} "
                                 f"(a jump of {mpmath.nstr(jump, 6)} rad)")
        if seg[0] == "line":
            _, th, L = seg
            if not L > 0:
                raise ValueError(f"track.segments[{n}].length must be > 0")
            c, sn = mpmath.cos(th), mpmath.sin(th)
            pieces.append(_Piece("line", s, s + L, px - r * sn, py + r * c, mpmath.mpf(0), th))
            px, py, s = px + L * c, py + L * sn, s + L
            continue
        _, R, side, a0, a1 = seg
        if not (R > 0 and a1 > a0):
            raise ValueError(f"track.segments[{n}] needs radius > 0 and end > start")
        if side == "concave":
            rho = R - r
            if not rho > 0:
                raise ValueError(f"the body (r = {mpmath.nstr(r, 6)}) does not fit in concave segment {n}")
            ox, oy = px - R * mpmath.sin(a0), py + R * mpmath.cos(a0)
            px, py = ox + R * mpmath.sin(a1), oy - R * mpmath.cos(a1)
        else:
            rho = R + r
            ox, oy = px - R * mpmath.sin(a0), py - R * mpmath.cos(a0)
            px, py = ox + R * mpmath.sin(a1), oy + R * mpmath.cos(a1)
        length = rho * (a1 - a0)
        pieces.append(_Piece(side, s, s + length, ox, oy, rho, a0))
        s += length
    return pieces


def _piece_at(pieces: list[_Piece], s) -> _Piece:
    """The piece holding s: a junction belongs to the piece after it; outside the
    chain the first or the last piece is extended."""
    for piece in reversed(pieces[1:]):
        if s >= piece.s0:
            return piece
    return pieces[0]


# ------------------------------------------------------------------ potential

def _check_keys(track: dict) -> str:
    if not isinstance(track, dict):
        raise ValueError(f"track must be a dict (a scene file's [track] table), got {type(track).__name__}")
    kind = track.get("type")
    if kind not in TRACK_KEYS:
        raise ValueError(f"track.type must be one of {', '.join(TRACK_KEYS)}, got {kind!r}")
    unknown = set(track) - TRACK_KEYS[kind]
    if unknown:
        raise ValueError(f"track: unknown keys {sorted(unknown)} for type {kind!r}")
    return kind


def _centre_function(track: dict, r):
    """(centre(q) -> (x_C, y_C), default domain of q) for a body of radius r."""
    kind = _check_keys(track)
    if kind == "curve":
        f = compile_expression(track.get("y"))

        def centre(x):
            fx = _real(f(x), f"x = {mpmath.nstr(x, 10)}")
            d1 = _real(mpmath.diff(f, x), f"x = {mpmath.nstr(x, 10)}")
            w = mpmath.sqrt(1 + d1 * d1)
            return x - r * d1 / w, fx + r / w

        domain = None
        if "x_min" in track and "x_max" in track:
            domain = (_num(track["x_min"], "track.x_min"), _num(track["x_max"], "track.x_max"))
        return centre, domain
    pieces = _chain(track, r)

    def centre(s):
        return _piece_at(pieces, s).centre(s)

    return centre, (pieces[0].s0, pieces[-1].s1)


def potential(track: dict, radius, omega, axis_x=0, g="9.81"):
    """V/m(q) = g y_C - 1/2 Omega^2 (x_C - a)^2 and the track's domain of q.

    Call (and evaluate) inside ``mpmath.workdps``: numbers are read at the
    working precision.
    """
    r = _num(radius, "radius")
    if r < 0:
        raise ValueError("radius must be >= 0")
    om2, a, gg = _num(omega, "omega") ** 2, _num(axis_x, "axis_x"), _num(g, "g")
    centre, domain = _centre_function(track, r)

    def V(q):
        x_c, y_c = centre(q)
        return gg * y_c - om2 * (x_c - a) ** 2 / 2

    return V, domain


def equilibrium_roots(track: dict, radius, omega, axis_x=0, g="9.81", guesses=(),
                      scan: int = 0, domain=None) -> list[mpmath.mpf]:
    """Roots of dV/dq near each guess (secant at 40 digits), plus, with ``scan`` > 0,
    roots bracketed by an independent scan of that many points over ``domain``.

    ``track`` is a plain dict in the form of a scene file's ``[track]`` table
    (``type`` curve, arcs or three_arcs; numbers as numbers or numeric
    strings, each read as ``mpmath.mpf(str(value))``). ``radius`` is the
    body's radius (0: a particle), ``omega`` the plane's rotation rate about
    the vertical line x = ``axis_x``. q is the contact abscissa x on a curve
    and the arc length s of the centre's path (0 at the chain's start) on an
    arc chain. ``domain`` defaults to [x_min, x_max] on a curve and to the
    whole chain on arcs.
    """
    with mpmath.workdps(DIGITS):
        V, default_domain = potential(track, radius, omega, axis_x, g)

        def dV(q):
            return mpmath.diff(V, q)

        roots = [mpmath.findroot(dV, _num(q0, "guess")) for q0 in guesses]
        if scan:
            if scan < 2:
                raise ValueError("scan needs at least 2 points")
            if domain is None:
                if default_domain is None:
                    raise ValueError("scan needs a domain (the curve has no x_min, x_max)")
                lo, hi = default_domain
            else:
                lo, hi = (_num(v, "domain") for v in domain)
            qs = [lo + (hi - lo) * k / (scan - 1) for k in range(scan)]
            vals = [dV(q) for q in qs]
            for q1, q2, v1, v2 in zip(qs, qs[1:], vals, vals[1:]):
                if v1 * v2 < 0:
                    roots.append(mpmath.findroot(dV, (q1, q2), solver="anderson"))
        return roots
