"""The equilibria reference shares no code with the layers it checks, and is right
where the answer is known in closed form."""

from __future__ import annotations

import ast
from pathlib import Path

import mpmath
import pytest

from heyroll.reference.equilibria import compile_expression, equilibrium_roots, potential

REFERENCE = Path(__file__).resolve().parents[1] / "heyroll" / "reference"
PACKAGE = "heyroll.reference"
FORBIDDEN = ("heyroll.model", "heyroll.simulation", "heyroll.interfaces", "heyroll.analysis")


def _imported_modules(source: str) -> list[str]:
    """Every module an import in ``source`` (a module of heyroll.reference) can reach, as
    absolute dotted names; ``from X import name`` gives both X and X.name (name may be a module)."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out += [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = PACKAGE.split(".")  # every module sits directly in heyroll.reference
                base = ".".join(parts[: max(len(parts) - (node.level - 1), 0)])
                module = ".".join(p for p in (base, node.module) if p)
            else:
                module = node.module or ""
            out.append(module)
            out += [f"{module}.{alias.name}" for alias in node.names]
        elif isinstance(node, ast.Call):
            # dynamic imports: __import__("...") / importlib.import_module("...")
            fn = node.func
            name = fn.id if isinstance(fn, ast.Name) else fn.attr if isinstance(fn, ast.Attribute) else ""
            if name in ("__import__", "import_module"):
                arg = node.args[0] if node.args else None
                out.append(arg.value if isinstance(arg, ast.Constant) and isinstance(arg.value, str)
                           else "<dynamic import>")
    return out


def _forbidden(module: str) -> bool:
    if module == "<dynamic import>":
        return True
    return any(module == f or module.startswith(f + ".") for f in FORBIDDEN)


@pytest.mark.parametrize("text", [
    "from ..model import expression", "from ..model.tracks import ArcChainTrack", "from .. import model",
    "from .. import simulation as sim", "import heyroll.model.paths", "from heyroll import analysis",
    "from heyroll.simulation.driver import simulate", "from ..interfaces.cli import main",
    "import importlib\nimportlib.import_module('heyroll.model')", "__import__(name)",
])
def test_resolver_catches_every_form(text):
    assert any(_forbidden(m) for m in _imported_modules(text)), text


@pytest.mark.parametrize("text", ["from .pendulum import ExactPendulum", "import mpmath", "from .. import errors",
                                  "from heyroll.reference import series", "from . import collisions"])
def test_resolver_allows_the_rest(text):
    assert not any(_forbidden(m) for m in _imported_modules(text)), text


@pytest.mark.parametrize("path", sorted(REFERENCE.glob("*.py")), ids=lambda p: p.name)
def test_reference_imports_no_engine_layer(path):
    bad = [m for m in _imported_modules(path.read_text(encoding="utf-8")) if _forbidden(m)]
    assert not bad, f"{path.name} imports {bad}: heyroll.reference must stay independent"


def test_reference_modules_found():
    assert (REFERENCE / "equilibria.py").exists() and len(list(REFERENCE.glob("*.py"))) >= 4


# ---------------------------------------------------------------- closed forms

TOL = mpmath.mpf(10) ** -30


def _close(a, b, tol=TOL):
    return abs(mpmath.mpf(a) - mpmath.mpf(b)) < tol


def _unique(roots, tol=mpmath.mpf(10) ** -20):
    out = []
    for q in sorted(roots):
        if not out or abs(q - out[-1]) > tol:
            out.append(q)
    return out


PARABOLA = {"type": "curve", "y": "x**2", "x_min": "-1", "x_max": "1"}


@pytest.mark.parametrize("radius", ["0", "0.05"])
def test_parabola_at_rest_has_its_equilibrium_at_the_vertex(radius):
    roots = equilibrium_roots(PARABOLA, radius, 0, guesses=["0.3", "-0.2"], scan=40)
    assert roots and all(abs(q) < TOL for q in roots)
    assert len(_unique(roots)) == 1


def test_quartic_in_a_rotating_plane():
    # V/m = g x^4/4 - omega^2 x^2/2: g x^3 = omega^2 x, so x = 0, +-omega/sqrt(g)
    track = {"type": "curve", "y": "x**4/4", "x_min": -2, "x_max": 2}
    omega, g = "3", "9.81"
    roots = equilibrium_roots(track, 0, omega, 0, g, guesses=["0.9", "-0.9", "0.05"], scan=80)
    with mpmath.workdps(50):
        x_star = mpmath.mpf(omega) / mpmath.sqrt(mpmath.mpf(g))
    assert _close(roots[0], x_star) and _close(roots[1], -x_star) and _close(roots[2], 0)
    found = _unique(roots[3:])
    assert len(found) == 3
    for q, expected in zip(found, (-x_star, 0, x_star)):
        assert _close(q, expected)


def test_eccentric_axis_shifts_the_quartic_root():
    # axis at a: g x^3 = omega^2 (x - a); check the root is one of the cubic's
    track = {"type": "curve", "y": "x**4/4"}
    roots = equilibrium_roots(track, 0, "2", "0.1", guesses=["0.5"])
    with mpmath.workdps(40):
        x = roots[0]
        assert abs(mpmath.mpf("9.81") * x**3 - 4 * (x - mpmath.mpf("0.1"))) < mpmath.mpf(10) ** -32


def _circle_track(R="1"):
    """One concave arc, phi = -pi..pi. Its surface point at phi = -pi is O + R (0, 1):
    starting the chain at (0, R) puts the circle's centre O at the origin."""
    with mpmath.workdps(50):
        pi = str(mpmath.pi)
    return {"type": "arcs", "start_x": 0, "start_y": R,
            "segments": [{"kind": "arc", "radius": R, "side": "concave", "start": "-" + pi, "end": pi}]}


def _inner(track, radius, margin="0.01"):
    """The track's domain less a margin at each end: the ends of a full circle (and the
    tops of the three-arc bowls) are equilibria themselves, which a scan would catch only
    by the sign of rounding noise."""
    with mpmath.workdps(40):
        _, (lo, hi) = potential(track, radius, 0)
        return lo + mpmath.mpf(margin), hi - mpmath.mpf(margin)


@pytest.mark.parametrize("radius", ["0", "0.05", "0.3"])
def test_circle_at_rest_has_its_equilibrium_at_the_lowest_point(radius):
    R = mpmath.mpf(1)
    roots = equilibrium_roots(_circle_track(), radius, 0, guesses=["2.5"], scan=50,
                              domain=_inner(_circle_track(), radius))
    with mpmath.workdps(40):
        expected = (R - mpmath.mpf(radius)) * mpmath.pi
    assert roots and all(_close(q, expected) for q in roots)


def test_circle_geometry_lowest_point_and_start():
    with mpmath.workdps(40):
        V, (lo, hi) = potential(_circle_track(), "0.2", 0, g="1")
        rho = mpmath.mpf("0.8")
        assert _close(lo, 0) and _close(hi, 2 * mpmath.pi * rho)
        assert _close(V(0), rho)                       # the centre starts at the top: y_C = R - r
        assert _close(V(mpmath.pi * rho), -rho)        # and is lowest half way


def test_rotating_circle_closed_form():
    # centre at rho (sin phi, -cos phi) about the axis through O: cos phi = g / (omega^2 rho)
    r, omega, g = "0.1", "5", "9.81"
    with mpmath.workdps(50):
        rho = 1 - mpmath.mpf(r)
        phi = mpmath.acos(mpmath.mpf(g) / (mpmath.mpf(omega) ** 2 * rho))
        expected = sorted([rho * (mpmath.pi - phi), rho * mpmath.pi, rho * (mpmath.pi + phi)])
    roots = _unique(equilibrium_roots(_circle_track(), r, omega, 0, g, scan=60, domain=_inner(_circle_track(), r)))
    assert len(roots) == 3
    for q, e in zip(roots, expected):
        assert _close(q, e)


def test_line_in_a_rotating_plane():
    # on a line at angle th: g sin th = omega^2 (x_C - a) cos th, x_C = s cos th - r sin th
    th, r, omega, a = mpmath.mpf("0.3"), mpmath.mpf("0.05"), mpmath.mpf("4"), mpmath.mpf("0.1")
    track = {"type": "arcs", "start_x": "0", "start_y": "0",
             "segments": [{"kind": "line", "angle": "0.3", "length": "2"}]}
    roots = equilibrium_roots(track, "0.05", "4", "0.1", guesses=["0.5"], scan=20)
    with mpmath.workdps(50):
        expected = (a + mpmath.mpf("9.81") * mpmath.tan(th) / omega**2 + r * mpmath.sin(th)) / mpmath.cos(th)
    assert len(roots) == 2 and all(_close(q, expected) for q in roots)


def test_three_arcs_at_rest():
    # bowl bottoms (phi = 0 on arcs 1 and 3) and the hump's top (psi = 0)
    R, R0, b, r = (mpmath.mpf(v) for v in ("1", "0.5", "0.2", "0.05"))
    track = {"type": "three_arcs", "radius": "1", "hump_radius": "0.5", "beta": "0.2", "sides": "two"}
    roots = _unique(equilibrium_roots(track, "0.05", 0, scan=200, domain=_inner(track, "0.05")))
    with mpmath.workdps(50):
        half = mpmath.pi / 2 - b
        arc1 = (R - r) * (mpmath.pi + half)
        expected = [(R - r) * mpmath.pi, arc1 + (R0 + r) * half,
                    arc1 + (R0 + r) * 2 * half + (R - r) * half]
    assert len(roots) == 3
    for q, e in zip(roots, expected):
        assert _close(q, e)


def test_three_arcs_equals_its_arcs_form_and_hump_centre_at_origin():
    with mpmath.workdps(40):
        b, R, R0 = mpmath.mpf("0.2"), mpmath.mpf(1), mpmath.mpf("0.5")
        half = mpmath.pi / 2 - b
        arcs = {"type": "arcs", "start_x": str(-(R + R0) * mpmath.cos(b)),
                "start_y": str((R + R0) * mpmath.sin(b) + R),
                "segments": [{"kind": "arc", "radius": 1, "side": "concave", "start": str(-mpmath.pi), "end": str(half)},
                             {"kind": "arc", "radius": "0.5", "side": "convex", "start": str(-half), "end": str(half)},
                             {"kind": "arc", "radius": 1, "side": "concave", "start": str(-half), "end": str(mpmath.pi)}]}
        three = {"type": "three_arcs", "radius": 1, "hump_radius": "0.5", "beta": "0.2"}
        Va, _ = potential(arcs, 0, "1.5", 0, g="1")
        Vt, (lo, hi) = potential(three, 0, "1.5", 0, g="1")
        for k in range(11):
            s = lo + (hi - lo) * k / 10
            assert abs(Va(s) - Vt(s)) < mpmath.mpf(10) ** -30
        # the particle on the hump's top is at (0, R0): V = g y = 0.5
        top = (R - 0) * (mpmath.pi + half) + R0 * half
        assert _close(Vt(top), R0)


def test_arc_chain_from_the_example_scene():
    # a line into a concave and a convex arc (examples/arc_chain.toml): the bowl's bottom
    track = {"type": "arcs", "start_x": -2.0, "start_y": 1.0, "sides": "one", "segments": [
        {"kind": "line", "angle": -0.5, "length": 1.0},
        {"kind": "arc", "radius": 1.0, "side": "concave", "start": -0.5, "end": 1.2},
        {"kind": "arc", "radius": 0.6, "side": "convex", "start": -1.2, "end": 0.9}]}
    r = mpmath.mpf("0.1")
    roots = _unique(equilibrium_roots(track, "0.1", 0, guesses=["1.5"], scan=100))
    with mpmath.workdps(50):
        bottom = 1 + (1 - r) * mpmath.mpf("0.5")
        top = 1 + (1 - r) * mpmath.mpf("1.7") + (mpmath.mpf("0.6") + r) * mpmath.mpf("1.2")
    assert len(roots) == 2 and _close(roots[0], bottom) and _close(roots[1], top)


def test_kinked_chain_is_rejected():
    track = {"type": "arcs", "segments": [{"kind": "line", "angle": 0, "length": 1},
                                          {"kind": "arc", "radius": 1, "side": "concave", "start": "0.1", "end": 1}]}
    with pytest.raises(ValueError, match="tangent"):
        equilibrium_roots(track, 0, 0, guesses=[0.5])


# ---------------------------------------------------------------- the evaluator

def test_evaluator_values():
    with mpmath.workdps(40):
        f = compile_expression("0.5*x**2*(x**2 - 1)**2 + sin(x) - -cos(x)/exp(x) + sqrt(x) + 2**-1 + +x")
        x = mpmath.mpf("0.3")
        expected = (mpmath.mpf("0.5") * x**2 * (x**2 - 1) ** 2 + mpmath.sin(x) + mpmath.cos(x) / mpmath.exp(x)
                    + mpmath.sqrt(x) + mpmath.mpf("0.5") + x)
        assert abs(f(x) - expected) < mpmath.mpf(10) ** -38
        assert compile_expression("0.1")(x) == mpmath.mpf("0.1")  # decimal text, not the double
        assert compile_expression("-x**2")(x) == -(x**2)           # Python's precedence
        assert compile_expression("(-x)**3")(-x) == x**3


@pytest.mark.parametrize("text", [
    "__import__('os')", "__import__('os').system('true')", "x.real", "(x).__class__", "y", "pi",
    "sin", "os.sin(x)", "abs(x)", "x if x else 1", "[x]", "x[0]", "lambda: x", "x < 1", "x // 2",
    "x % 2", "1j", "0x10", "1_0", "True", "'x'", "sin(x, x)", "sin(x=x)", "x; x", "",
    "(lambda x: x)(x)", "exp.__call__(x)",
])
def test_evaluator_rejects(text):
    with pytest.raises(ValueError):
        compile_expression(text)


def test_track_rejects_bad_input():
    with pytest.raises(ValueError):
        equilibrium_roots({"type": "curve", "y": "__import__('os').getcwd()"}, 0, 0, guesses=[0])
    with pytest.raises(ValueError):
        equilibrium_roots({"type": "curve", "y": "x**2", "xmin": 0}, 0, 0, guesses=[0])
    with pytest.raises(ValueError):
        equilibrium_roots({"type": "circle", "radius": 1}, 0, 0, guesses=[0])
    with pytest.raises(ValueError):
        equilibrium_roots(PARABOLA, True, 0, guesses=[0])
