"""Property-based fuzzing (hypothesis) of the engine, the scene loader and the CLI.

Properties:

* random scenes (2-4 bodies of every shape, particles under Newton's laws,
  radii, masses, every law, k in [0, 1], neighbours far apart, nearly or
  exactly touching (gap 0.0 in double), energies below and above the top,
  one- or two-sided tracks, sometimes friction, both inconsistency policies):
  every run ends with a status of heyroll's Status enum and a message, never
  ``failed`` or ``overlap``; no interpenetration beyond 1e-12 rad at any
  recorded collision (before and after) nor on dense samples of every branch;
  energy never increases across a collision (under the laws that cannot
  create energy, see conserves_mechanical_energy_bound) nor over the run;
* the scene loader on malformed TOML (mutated keys and values: wrong types,
  NaN/inf, negative, huge and tiny numbers, unknown keys, broken syntax) and
  on arbitrary text: a scene, or a SceneError (a ValueError) naming the field
  in one line; nothing else;
* ``heyroll run`` on malformed scene files: exit code 2, one line on stderr and
  no file written for bad input; 0 or 1 otherwise; never a traceback.

Every test is deterministic (derandomize=True, no example database): CI
draws the same examples every time. Volume of the default run (EXAMPLES):
300 random scenes, 1500 malformed scene files, 400 arbitrary texts, 50 CLI
runs (+15 fixed bad values), ~20 s on 2 cores. The larger run is
``test_fuzz_volume``, marked slow (``python -m pytest -m slow
tests/test_fuzz.py -s`` prints examples and wall time per property;
HEYROLL_FUZZ_REPORT=FILE writes them as JSON): SLOW_EXAMPLES, other seeds,
plus 100 random scenes in quad / MPFR precision; measured 614 s (scenes
2000 in 121 s, quad/MPFR 100 in 376 s, loader 20000 in 99 s, text 5000 in
8 s, CLI 400 in 7 s), all passing.

What the fuzz found (regression tests in test_hard_cases.py): the eight
engine bugs that were strict xfails there; a plastic collision where the gap
acceleration changes sign (contact criterion now on the gap's jerk); a run
that heyoka cannot advance (zero-length steps with a track-force event of
1e29: now status failed, before a hang); and in the loader a TypeError for
``track.type = []`` (now a SceneError; HANDFUL below). Found by hand and
fuzzed since (slow run): double constants in quad and MPFR runs, which hid
same-instant contacts.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
import tempfile
import time

import mpmath
import numpy as np
import pytest
from hypothesis import HealthCheck, assume, event, given, seed, settings
from hypothesis import strategies as st

import heyroll
from heyroll import Body, CircleTrack, RunSettings, Scene, SceneError, Status, make_law, parse_scene
from heyroll.interfaces.cli import main as cli_main
from heyroll.model.laws import conserves_mechanical_energy_bound
from heyroll.simulation.trajectory import sample_branches

#: Examples per property in the default run (tests/test_fuzz.py takes ~30 s on 2 cores).
EXAMPLES = {"scenes": 300, "loader": 1500, "text": 400, "cli": 50, "path_loader": 400, "path_cli": 30}
#: ... and in the slow run (test_fuzz_volume).
SLOW_EXAMPLES = {"scenes": 2000, "scenes_extended": 100, "loader": 20000, "text": 5000, "cli": 400,
                 "path_loader": 5000, "path_cli": 300}

FUZZ = dict(
    deadline=None, derandomize=True, database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much, HealthCheck.data_too_large],
)
GAP_FLOOR = -1e-12
#: Per random scene: a short run, a bounded number of collisions.
T_END = (0.5, 2.0)
MAX_COLLISIONS = 60


# -- random scenes ------------------------------------------------------------------

SHAPES = ("solid_sphere", "hollow_sphere", "disk", "ring", "particle")
LAWS = ("hedrih", "newton", "newton_generalized")


def _up(x) -> float:
    """The double nearest to mpf x, rounded up (never overlapping when used as a position)."""
    f = float(x)
    return f if mpmath.mpf(f) >= x else math.nextafter(f, math.inf)


def _exact_touch(phi: float, beta) -> float:
    """A position touching phi's body: gap >= 0 exactly, and 0.0 evaluated in double where possible."""
    x = _up(mpmath.mpf(phi) + beta)
    for _ in range(4):
        if (x - phi) + (-float(beta)) == 0.0:
            return x
        x = math.nextafter(x, math.inf)
    return _up(mpmath.mpf(phi) + beta)


@st.composite
def random_scenes(draw):
    law = draw(st.sampled_from(LAWS))
    n = draw(st.integers(2, 4))
    shapes = SHAPES if law != "hedrih" else SHAPES[:-1]  # the rolling law needs a radius
    track = CircleTrack.of_radius(1)
    bodies = []
    for _ in range(n):
        shape = draw(st.sampled_from(shapes))
        radius = 0 if shape == "particle" else draw(st.floats(0.02, 0.25))
        bodies.append(Body.of_shape(shape, radius, mass=draw(st.floats(0.1, 10.0))))
    # Counter-clockwise, without overlap; some neighbours start exactly touching
    # (gap 0.0 in double), some within the contact tolerance, some nearly.
    phi = [draw(st.floats(-1.8, 0.0))]
    for a, b in zip(bodies, bodies[1:]):
        with mpmath.workprec(256):
            beta = track.contact_angle(a, b)
            extra = draw(st.one_of(st.sampled_from((0.0, 1e-15, 1e-12, 1e-9)), st.floats(1e-15, 0.4)))
            phi.append(_exact_touch(phi[-1], beta) if extra == 0.0 else _up(mpmath.mpf(phi[-1]) + beta + extra))
    assume(phi[-1] <= 2.2)
    g = mpmath.mpf("9.81")
    # Energy of each body: a fraction of what reaches its top (2 W); above 1 it
    # goes over. Or its neighbour's rate give or take a little: a touching pair
    # that opens (or closes) slowly, the hardest case for event detection.
    dphi = []
    for b, p in zip(bodies, phi):
        G, W = float(track.generalized_mass(b)), float(track.weight_moment(b, g))
        if dphi and draw(st.integers(0, 3)) == 0:
            dphi.append(dphi[-1] + draw(st.sampled_from((0.0, 1e-12, -1e-12, 0.01, -0.01, 0.05))))
            continue
        room = draw(st.sampled_from((0.0, 0.3, 0.9, 0.99, 1.2))) * 2 * W - W * (1 - math.cos(p))
        dphi.append(draw(st.floats(-1.0, 1.0)) * math.sqrt(2 * max(room, 0.0) / G))
    sides = draw(st.sampled_from(("two",) * 5 + ("one",)))
    friction = draw(st.floats(0.05, 1.0)) if draw(st.integers(0, 5)) == 0 else None
    k = draw(st.one_of(st.just(0.0), st.just(1.0), st.floats(0.0, 1.0)))
    try:
        return Scene.make(
            track=track, bodies=bodies, phi=phi, dphi=dphi, law=make_law(law, k),
            run=RunSettings.make(draw(st.floats(*T_END)), MAX_COLLISIONS), track_sides=sides, friction=friction,
            on_inconsistent=draw(st.sampled_from(("newton",) * 4 + ("error",))),
        )
    except SceneError as exc:  # a combination the model rejects (it says why): not a run to fuzz
        event(f"scene rejected: {exc.field}")
        assume(False)


def pair_gaps(sc, states) -> np.ndarray:
    """Gaps (rows: states, columns: scene pairs), rad."""
    states = np.atleast_2d(np.asarray(states, dtype=float))
    return np.array([states[:, p.j] - states[:, p.i] + float(p.gap_constant()) for p in sc.pairs]).T


def check_scene(sc: Scene, precision: str = "double") -> None:
    result = heyroll.simulate(sc, precision=precision)
    event(f"status {result.status.value}")
    event(f"collisions {'0' if not result.n_collisions else '1-9' if result.n_collisions < 10 else '10+'}")
    event(f"contacts {'yes' if result.contact_intervals else 'no'}")
    # Every run ends with a status and says why.
    assert isinstance(result.status, Status)
    assert isinstance(result.message, str) and result.message.strip()
    assert result.status not in (Status.FAILED, Status.OVERLAP, Status.INTERRUPTED), result.message
    t_end, limit = float(sc.run.t_end), sc.run.max_collisions
    assert result.n_collisions <= limit
    assert 0 <= float(result.t_final) <= t_end
    if result.status is Status.COMPLETED:
        assert float(result.t_final) == pytest.approx(t_end, abs=1e-12)
    if result.status is Status.MAX_COLLISIONS:
        assert result.n_collisions == limit
    times = np.asarray(result.times, dtype=float)
    assert np.all(np.diff(times) >= 0) and (times.size == 0 or 0 <= times[0] <= times[-1] <= float(result.t_final))
    assert np.all(np.isfinite(np.asarray(result.final_state, dtype=float)))

    # No interpenetration: at every collision (before and after) and along every branch.
    for states in (result.states_before, result.states_after, result.final_state):
        if np.size(states):
            assert pair_gaps(sc, states).min() >= GAP_FLOOR
    for branch in sample_branches(result, points=30):
        gaps = pair_gaps(sc, branch.states)
        assert gaps.min() >= GAP_FLOOR, (float(gaps.min()), float(branch.times[0]))

    # Energy never grows across a collision under a law that cannot create it
    # (Newton's law on centre speeds with unequal kappa can, by design; the
    # fallback and cluster laws, flags 1 and 2, cannot), nor over the run.
    table = result.collision_table()
    bounded = np.array([conserves_mechanical_energy_bound(sc.law, sc.bodies[p.i], sc.bodies[p.j], sc.sigma(p.i), sc.sigma(p.j))
                        for p in sc.pairs])
    scale = float(sum(sc.track.weight_moment(b, sc.g) for b in sc.bodies)) + abs(result.energy_initial)
    if table.size:
        rows = bounded[result.pair_numbers] | (table["law_flag"] != 0)
        gain = (table["energy_after"] - table["energy_before"])[rows]
        assert np.all(gain <= 1e-12 * scale), float(gain.max())
    if bounded.all():
        assert result.energy_final - result.energy_initial <= 1e-9 * scale


@settings(max_examples=EXAMPLES["scenes"], **FUZZ)
@given(random_scenes())
def test_random_scenes_run_cleanly(sc):
    check_scene(sc)


def check_scene_extended(case) -> None:
    check_scene(*case)


#: The same scenes in quad and MPFR precision (the engine's constants and
#: tolerances follow the run's type: a double constant once hid every
#: same-instant contact from a quad run). About 3 s an example (compiling
#: real128 / MPFR code for each new shape): in the slow run only.
EXTENDED_SCENES = st.tuples(random_scenes(), st.sampled_from(("quad", "mp:80")))


# -- the scene loader on malformed input -----------------------------------------------

#: A valid scene as (table header or None, key, value text) lines.
BASE = [
    (None, "name", '"fuzz"'),
    (None, "g", "9.81"),
    ("[track]", "type", '"circle"'),
    ("[track]", "radius", "1.0"),
    ("[track]", "sides", '"two"'),
    ("[[bodies]]", "shape", '"solid_sphere"'),
    ("[[bodies]]", "radius", "0.1"),
    ("[[bodies]]", "mass", "1.0"),
    ("[[bodies]]", "phi", "-0.5"),
    ("[[bodies]]", "dphi", "0.0"),
    ("[[bodies]]#2", "shape", '"disk"'),
    ("[[bodies]]#2", "radius", "0.15"),
    ("[[bodies]]#2", "density", "7850"),
    ("[[bodies]]#2", "phi", "0.5"),
    ("[[bodies]]#2", "omega", "0.3"),
    ("[collision]", "law", '"hedrih"'),
    ("[collision]", "restitution", "0.8"),
    ("[collision]", "on_inconsistent", '"newton"'),
    ("[run]", "t_end", "1.0"),
    ("[run]", "max_collisions", "20"),
]
KEYS = sorted({k for _, k, _ in BASE} | {"kappa", "friction", "bodies", "track", "collision", "run", "frame"})
#: Values a double can hold.
VALUES = [
    "nan", "+nan", "-nan", "inf", "+inf", "-inf", "0", "0.0", "-0.0", "-1", "-0.5", "-7850", "1", "2", "0.3", "0.99",
    "1.5", "10", "1e-300", "1e300", "1e308", "-1e308", "4e-320", "123456789012345678901234567890",
    "-9223372036854775809", "9223372036854775808", "true", "false", '"text"', '""', '"1.0"', "[1, 2]", "[]",
    "{ a = 1 }", "{}", "1979-05-27", "07:32:00", "1979-05-27T07:32:00Z", "0x1F", "0o17", "0b101", "1_000",
    '"circle"', '"curve"', '"arcs"', '"three_arcs"', '"particle"', '"ring"', '"one"', '"two"', '"newton"',
    '"newton_generalized"', '"error"', '"hedrih"',
    "3.141592653589793", "6.3", "-3.2", '"\\u0000"', "'''multi\nline'''",
]
#: Values beyond a double's range (0 or inf as doubles).
EXTREME = ["1e400", "-1e400", "1e-400", "-1e-400", "1e99999"]
GARBAGE = ["=", "[", "]", "[[", '"', "\n", "#", "= =", "[track", "\x00", "\ufeff", "é", "\r", "{", ".", "\t"]


#: The same, on each path track type (issue 13: the loader and the CLI fuzzed on every track).
PATH_BASES = {
    "arcs": [
        (None, "name", '"fuzz-arcs"'),
        ("[track]", "type", '"arcs"'), ("[track]", "start_x", "-2.0"), ("[track]", "start_y", "1.0"),
        ("[track]", "limiter_restitution", "0.8"),
        ("[[track.segments]]", "kind", '"line"'), ("[[track.segments]]", "angle", "-0.5"),
        ("[[track.segments]]", "length", "1.0"),
        ("[[track.segments]]#2", "kind", '"arc"'), ("[[track.segments]]#2", "radius", "1.0"),
        ("[[track.segments]]#2", "side", '"concave"'), ("[[track.segments]]#2", "start", "-0.5"),
        ("[[track.segments]]#2", "end", "1.2"),
        ("[[bodies]]", "shape", '"solid_sphere"'), ("[[bodies]]", "radius", "0.1"), ("[[bodies]]", "mass", "1.0"),
        ("[[bodies]]", "s", "0.2"), ("[[bodies]]", "ds", "0.0"),
        ("[[bodies]]#2", "shape", '"disk"'), ("[[bodies]]#2", "radius", "0.08"), ("[[bodies]]#2", "mass", "2.0"),
        ("[[bodies]]#2", "segment", "2"), ("[[bodies]]#2", "angle", "0.3"),
        ("[collision]", "restitution", "0.7"), ("[run]", "t_end", "1.0"),
    ],
    "three_arcs": [
        ("[track]", "type", '"three_arcs"'), ("[track]", "radius", "1.0"), ("[track]", "hump_radius", "0.5"),
        ("[track]", "beta", "0.2"),
        ("[[bodies]]", "shape", '"disk"'), ("[[bodies]]", "radius", "0.05"), ("[[bodies]]", "mass", "1.0"),
        ("[[bodies]]", "segment", "1"), ("[[bodies]]", "angle", "-0.5"),
        ("[[bodies]]#2", "shape", '"ring"'), ("[[bodies]]#2", "radius", "0.08"), ("[[bodies]]#2", "mass", "2.0"),
        ("[[bodies]]#2", "segment", "1"), ("[[bodies]]#2", "angle", "0.5"),
        ("[run]", "t_end", "1.0"),
    ],
    "curve": [
        ("[track]", "type", '"curve"'), ("[track]", "y", '"0.5*x**2*(x**2 - 1)**2"'),
        ("[track]", "x_min", "-1.6"), ("[track]", "x_max", "1.6"), ("[track]", "sides", '"two"'),
        ("[frame]", "omega", "3.0"), ("[frame]", "axis_x", "0.0"),
        ("[[bodies]]", "shape", '"disk"'), ("[[bodies]]", "radius", "0.05"), ("[[bodies]]", "mass", "1.0"),
        ("[[bodies]]", "x", "0.3"), ("[[bodies]]", "dx", "0.0"),
        ("[[bodies]]#2", "shape", '"disk"'), ("[[bodies]]#2", "radius", "0.05"), ("[[bodies]]#2", "mass", "1.5"),
        ("[[bodies]]#2", "x", "1.1"),
        ("[collision]", "law", '"newton"'), ("[run]", "t_end", "1.0"),
    ],
}
#: Curve expressions a hostile file may hold (each must load or be one line naming track.y).
EXPRESSIONS = ['"1/0"', '"2**10000*x**2"', '"x/(x-x)"', '"sqrt(-1-x**2)"', '"exp(1000*x)"', '"1"', '"0.1*x"',
               '"((((x))))"', '"x**0.5"', '"sin(x)**-1"', '"' + "+".join(["x"] * 600) + '"', '"x**x"', '"1e400*x"']


@st.composite
def malformed_scene_text(draw, values=tuple(VALUES + EXTREME), mutations=4, garble=True, base=None):
    lines = list(BASE if base is None else base)
    for _ in range(draw(st.integers(1, mutations))):
        kind = draw(st.sampled_from(("value", "value", "value", "delete", "add", "rename", "float", "int")))
        n = draw(st.integers(0, len(lines) - 1))
        section, key, value = lines[n]
        if kind == "value":
            lines[n] = (section, key, draw(st.sampled_from(values)))
        elif kind == "float":
            x = draw(st.floats(allow_nan=True, allow_infinity=True))
            text = "nan" if math.isnan(x) else ("inf" if x > 0 else "-inf") if math.isinf(x) else repr(x)
            lines[n] = (section, key, text)
        elif kind == "int":
            lines[n] = (section, key, str(draw(st.integers(-(2**80), 2**80))))
        elif kind == "delete":
            del lines[n]
            if not lines:
                break
        elif kind == "add":
            invented = st.from_regex(r"[A-Za-z_][A-Za-z0-9_-]{0,8}", fullmatch=True)
            new_key = draw(st.one_of(st.sampled_from(KEYS), invented))
            lines.insert(n, (section, new_key, draw(st.sampled_from(values))))
        else:
            lines[n] = (section, draw(st.sampled_from(KEYS)), value)
    text = _render(lines)
    if garble and draw(st.integers(0, 9)) == 0:  # break the syntax somewhere
        at = draw(st.integers(0, len(text)))
        text = text[:at] + draw(st.sampled_from(GARBAGE)) + text[at:]
    return text


def _render(lines) -> str:
    out, current = [], None
    for section, key, value in lines:
        if section != current:
            if section is not None:
                out.append(section.split("#")[0])
            current = section
        out.append(f"{key} = {value}")
    return "\n".join(out) + "\n"


def _load(text: str, record: bool = True):
    """Load ``text``: a scene or a SceneError (one line, naming the field); anything else fails the test."""
    note = event if record else (lambda _: None)
    try:
        scene = parse_scene(text)
    except SceneError as exc:
        assert isinstance(exc, ValueError)
        root = exc.field.split("[")[0].split(".")[0]
        note(f"rejected: {root if root in {'name', 'g', 'track', 'bodies', 'collision', 'run'} else 'other'}")
        if not isinstance(exc, heyroll.SceneFileError):  # TOML syntax errors quote the parser's message
            assert str(exc).startswith(exc.field + ": ") and "\n" not in str(exc)
        return exc
    note("loaded")
    assert isinstance(scene, Scene)
    return scene


def check_loader(text: str) -> None:
    _load(text)


def test_base_scene_is_valid():
    assert isinstance(parse_scene(_render(BASE)), Scene)


@settings(max_examples=EXAMPLES["loader"], **FUZZ)
@given(malformed_scene_text())
def test_loader_accepts_or_rejects_with_scene_error(text):
    check_loader(text)


@settings(max_examples=EXAMPLES["text"], **FUZZ)
@given(st.text(max_size=400))
def test_loader_on_arbitrary_text(text):
    check_loader(text)


# -- the CLI on malformed scene files ------------------------------------------------------


def _cli(path: str, out: str, *extra) -> tuple[int, str]:
    stderr = io.StringIO()
    with contextlib.redirect_stderr(stderr), contextlib.redirect_stdout(io.StringIO()):
        try:
            code = cli_main(["run", path, "--out", out, "--no-figures", "--progress", "off", *extra])
        except SystemExit as exc:  # argparse
            code = exc.code
    return code, stderr.getvalue()


def _bounded_t_end(text: str) -> str:
    """0.5 s, or less for a scene that moves faster: a run of ~1e4 steps at most.

    The CLI runs what it is asked: g = 1e29 (periods of 1e-14 s) or a rate of
    1e16 rad/s (revolutions of 1e-16 s) for 1 s take ~1e15 steps. Cap at 1e3
    periods of the stiffest pendulum and 1e3 revolutions at the largest rate
    the scene's energy allows any body.
    """
    try:
        sc = parse_scene(text)
    except SceneError:
        return "0.5"
    if not isinstance(sc, Scene):
        return "0.5"
    with np.errstate(all="ignore"):
        G = np.array([float(sc.track.generalized_mass(b)) for b in sc.bodies])
        W = np.array([float(sc.track.weight_moment(b, sc.g)) for b in sc.bodies])
        energy = float(np.sum(G * np.array([float(x) for x in sc.dphi]) ** 2 / 2 + 2 * W))
        fastest = np.max(np.sqrt(2 * energy / G))
        stiffest = np.max(W / G)
        caps = [float(1e3 / np.sqrt(stiffest)), float(1e3 * 2 * np.pi / fastest)]  # inf: no cap
    # Numbers that overflow a double (a mass of 1e308: G = inf, nan here) leave no scale: a short run.
    return repr(min([0.5] + [1e-6 if math.isnan(c) or c <= 0 else c for c in caps]))


def check_cli(text: str) -> None:
    _check_cli_run(text, "--t-end", _bounded_t_end(text), "--max-collisions", "20")


def _check_cli_run(text: str, *options: str) -> None:
    """Run the CLI on ``text``: exit 0, 1 or 2, never a traceback; 2 (one line, nothing written)
    whenever the loader rejects the file; otherwise a summary on disk."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "scene.toml")
        with open(path, "w", encoding="utf-8", newline="") as f:
            f.write(text)
        code, stderr = _cli(path, os.path.join(tmp, "out"), *options)
        event(f"exit {code}")
        assert code in (0, 1, 2), (code, stderr)
        assert "Traceback" not in stderr
        if isinstance(_load(text, record=False), SceneError):
            assert code == 2
        if code == 2:
            assert stderr.startswith("heyroll: error: ") and stderr.count("\n") == 1, stderr
            assert sorted(os.listdir(tmp)) == ["scene.toml"]  # nothing written
        else:
            assert os.path.isfile(os.path.join(tmp, "out", "summary.json"))


@settings(max_examples=EXAMPLES["cli"], **FUZZ)
@given(malformed_scene_text(mutations=1, garble=False))
def test_cli_on_malformed_scene_files(text):
    check_cli(text)


@st.composite
def malformed_path_scene_text(draw, mutations=3, garble=True):
    kind = draw(st.sampled_from(sorted(PATH_BASES)))
    values = tuple(VALUES + EXTREME + (EXPRESSIONS if kind == "curve" else []))
    return draw(malformed_scene_text(values=values, mutations=mutations, garble=garble, base=PATH_BASES[kind]))


def test_path_bases_are_valid():
    for kind, lines in PATH_BASES.items():
        assert isinstance(parse_scene(_render(lines)), Scene), kind


@settings(max_examples=EXAMPLES["path_loader"], **FUZZ)
@given(malformed_path_scene_text())
def test_loader_on_every_path_track_type(text):
    check_loader(text)


def check_cli_path(text: str) -> None:
    """As check_cli, on a path scene: a short run, every event kind bounded."""
    _check_cli_run(text, "--t-end", "0.3", "--max-events", "2000")


@settings(max_examples=EXAMPLES["path_cli"], **FUZZ)
@given(malformed_path_scene_text(mutations=1, garble=False))
def test_cli_on_malformed_path_scene_files(text):
    check_cli_path(text)


HANDFUL = {
    "nan mass": [("[[bodies]]", "mass", "nan")],
    "negative radius": [("[[bodies]]", "radius", "-0.1")],
    "string restitution": [("[collision]", "restitution", '"0.8"')],
    "unknown key": [("[run]", "t_ending", "1.0")],
    "inf g": [(None, "g", "inf")],
    "boolean max_collisions": [("[run]", "max_collisions", "true")],
    "overlapping bodies": [("[[bodies]]", "phi", "0.45")],
    "t_end=1e400": [("[run]", "t_end", "1e400")],
    "g=1e-400": [(None, "g", "1e-400")],
    "R=1e400": [("[track]", "radius", "1e400")],
    "mass=1e400": [("[[bodies]]", "mass", "1e400")],
    "radius=1e-400": [("[[bodies]]", "radius", "1e-400")],
    "dphi=1e400": [("[[bodies]]", "dphi", "1e400")],
    "list track type": [("[track]", "type", "[1, 2]")],  # found by the loader fuzz: a TypeError before
    "table track type": [("[track]", "type", "{ a = 1 }")],
}


@pytest.mark.parametrize("name", sorted(HANDFUL))
def test_cli_rejects_bad_values_cleanly(name, tmp_path):
    lines = list(BASE)
    for section, key, value in HANDFUL[name]:
        at = [n for n, (s, k, _) in enumerate(lines) if (s, k) == (section, key)]
        if at:
            lines[at[0]] = (section, key, value)
        else:
            lines.append((section, key, value))
    path = tmp_path / "scene.toml"
    path.write_text(_render(lines))
    assert isinstance(_load(path.read_text(), record=False), SceneError)
    code, stderr = _cli(str(path), str(tmp_path / "out"))
    assert code == 2 and stderr.startswith("heyroll: error: ") and "Traceback" not in stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.toml"]


# -- the larger volume -----------------------------------------------------------------------


PROPERTIES = {
    "scenes": (check_scene, random_scenes()),
    "scenes_extended": (check_scene_extended, EXTENDED_SCENES),
    "loader": (check_loader, malformed_scene_text()),
    "text": (check_loader, st.text(max_size=400)),
    "cli": (check_cli, malformed_scene_text(mutations=1, garble=False)),
    "path_loader": (check_loader, malformed_path_scene_text()),
    "path_cli": (check_cli_path, malformed_path_scene_text(mutations=1, garble=False)),
}


def run_property(name: str, examples: int, seed_value: int) -> dict:
    """Run one property on ``examples`` examples drawn from ``seed_value``; its volume and wall time."""
    check, strategy = PROPERTIES[name]
    ran = [0]

    @seed(seed_value)
    @settings(max_examples=examples, **{**FUZZ, "derandomize": False})
    @given(strategy)
    def fuzz(x):
        check(x)
        ran[0] += 1

    started = time.perf_counter()
    fuzz()
    return {"property": name, "max_examples": examples, "examples_run": ran[0],
            "wall_time_s": round(time.perf_counter() - started, 1)}


@pytest.mark.slow
def test_fuzz_volume(record_property):
    """Every property at SLOW_EXAMPLES (other examples than the default run: another seed).

    ``python -m pytest -m slow tests/test_fuzz.py -s``; HEYROLL_FUZZ_REPORT=FILE
    also writes the volume as JSON.
    """
    report = [run_property(name, n, seed_value=20240 + k) for k, (name, n) in enumerate(SLOW_EXAMPLES.items())]
    for row in report:
        record_property(row["property"], json.dumps(row))
        print(f"fuzz {row['property']:>7}: {row['examples_run']} examples passed "
              f"(max_examples {row['max_examples']}) in {row['wall_time_s']} s")
        assert row["examples_run"] > 0
    if os.environ.get("HEYROLL_FUZZ_REPORT"):
        with open(os.environ["HEYROLL_FUZZ_REPORT"], "w", encoding="utf-8") as f:
            json.dump(report, f, indent=1)
