"""Scene files in TOML (read with the standard library's tomllib).

Numbers are parsed as decimals (``parse_float=Decimal``) so that a scene's
values reach every precision from their decimal text, not through a double.
Unknown keys are errors: a typo must never be silently ignored.
"""

from __future__ import annotations

import tomllib
from decimal import Decimal
from importlib import resources
from pathlib import Path

from ..errors import SceneError, SceneFileError
from ..model._numbers import is_finite, is_number, to_mpf, workprec
from ..model.bodies import Body, parse_shape
from ..model.laws import make_law
from ..model.forcing import Forcing
from ..model.frame import Frame
from ..model.scene import STANDARD_GRAVITY, RunSettings, Scene
from ..model.tracks import ArcChainTrack, CircleTrack, CurveTrack, ParametricTrack, Segment, ThreeArcTrack

#: "sweep": a scene file may hold the [sweep] table of `heyroll sweep` (heyroll.sweep.plan checks
#: its values); a single run ignores it, but its key names are checked here for every command, so
#: that a typo there is not passed silently by `heyroll run` (acceptance test).
TOP_KEYS = {"name", "g", "track", "bodies", "collision", "run", "frame", "sweep", "forcing"}
#: Keys of a scene file's [sweep] table (the sweep command's flags without dashes).
SWEEP_TABLE_KEYS = {"vary", "values", "random", "samples", "seed", "keep", "precision", "batch"}
TRACK_KEYS = {"type", "radius", "friction", "static_friction", "sides"}
TRACK_TYPES = ("circle", "curve", "arcs", "three_arcs", "parametric", "table")
#: Keys of each path track type (paper section 5).
PATH_TRACK_KEYS = {
    "curve": {"type", "y", "x_min", "x_max", "limiter_restitution", "sides", "friction", "static_friction"},
    "arcs": {"type", "segments", "start_x", "start_y", "limiter_restitution", "sides", "friction", "static_friction"},
    "three_arcs": {"type", "radius", "hump_radius", "beta", "limiter_restitution", "sides", "friction",
                   "static_friction"},
    "parametric": {"type", "x", "y", "u_min", "u_max", "limiter_restitution", "sides", "friction", "static_friction"},
}
SEGMENT_KEYS = {"arc": {"kind", "radius", "side", "start", "end"}, "line": {"kind", "angle", "length"}}
FRAME_KEYS = {"omega", "axis_x"}
#: slip: a rolling body's initial slip velocity w = v_C - r omega_P on a rough track (m/s, default 0: rolling).
BODY_SHAPE_KEYS = {"shape", "kappa", "radius", "mass", "density", "slip"}
#: [forcing] (see heyroll.model.forcing): kind = "force" | "base".
FORCING_KEYS = {"kind", "amplitude", "frequency", "phase", "direction", "bodies"}
BODY_KEYS = BODY_SHAPE_KEYS | {"phi", "dphi", "omega"}
#: Where a body starts on a path track: curve (contact abscissa x and its
#: rate), arc chain (arc length s of the centre's path, or a segment and the
#: angle on it: phi on concave arcs, psi on convex ones, distance on lines).
PATH_BODY_KEYS = {"curve": BODY_SHAPE_KEYS | {"x", "dx"}, "parametric": BODY_SHAPE_KEYS | {"u", "du"},
                  "arcs": BODY_SHAPE_KEYS | {"s", "ds", "segment", "angle", "dangle"}}
COLLISION_KEYS = {"law", "restitution", "on_inconsistent", "simultaneous"}
RUN_KEYS = {"t_end", "max_collisions"}


def load_scene(path: str | Path) -> Scene:
    """Read and check a scene file; raises SceneError (a ValueError) on bad input."""
    path = Path(path)
    return parse_scene(read_scene_text(path), source=str(path), default_name=path.stem)


def read_scene_text(path: Path) -> str:
    """A scene file's text; SceneFileError (one line) if it is missing or unreadable."""
    try:
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SceneFileError(str(path), "no such scene file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneFileError(str(path), f"cannot be read ({exc.__class__.__name__})") from None


def default_scene() -> Scene:
    """The built-in default scene: two solid balls of different radii in a circle."""
    text = resources.files("heyroll").joinpath("scenes/default.toml").read_text(encoding="utf-8")
    return parse_scene(text, source="<default scene>")


def default_scene_text() -> str:
    return resources.files("heyroll").joinpath("scenes/default.toml").read_text(encoding="utf-8")


def parse_scene(text: str, *, source: str = "<scene>", default_name: str = "scene") -> Scene:
    try:
        data = tomllib.loads(text, parse_float=Decimal)
    except tomllib.TOMLDecodeError as exc:
        raise SceneFileError(source, f"not valid TOML ({exc})") from None
    return scene_from_dict(data, default_name=default_name)


def scene_from_dict(data: dict, *, default_name: str = "scene") -> Scene:
    _no_unknown(data, TOP_KEYS, "")
    _no_unknown(_table(data, "sweep", required=False), SWEEP_TABLE_KEYS, "sweep")
    name = data.get("name", default_name)
    if not isinstance(name, str):
        raise SceneError("name", "must be a string")
    g = _number(data, "g", "", default=STANDARD_GRAVITY)
    track_table = _table(data, "track", required=True)
    if track_table.get("type") == "table":  # billiards (paper section 7)
        from .table_file import table_scene_from_dict

        return table_scene_from_dict(data, name)
    if isinstance(track_table.get("type"), str) and track_table["type"] in PATH_TRACK_KEYS:  # [] / {}: unhashable
        return _path_scene(data, track_table, name, g)
    frame = _frame(_table(data, "frame", required=False))
    track = _track(track_table)
    friction = _number(track_table, "friction", "track")
    sides = track_table.get("sides", "two")
    if not isinstance(sides, str):
        raise SceneError("track.sides", "must be a string: one | two")
    bodies_data = _bodies_list(data)
    bodies, phis, dphis = [], [], []
    for n, entry in enumerate(bodies_data, start=1):
        body, phi, dphi = _body(entry, f"bodies[{n}]", track)
        bodies.append(body)
        phis.append(phi)
        dphis.append(dphi)
    law, policy, settings = _collision_and_run(data)
    return Scene.make(
        track, bodies, phis, dphis, law=law, g=g, run=settings, name=name,
        friction=friction, on_inconsistent=policy, track_sides=sides, frame=frame,
        simultaneous=_simultaneous(data), **_rough(data, track_table, bodies_data),
    )


def _rough(data: dict, track_table: dict, bodies_data: list) -> dict:
    """Static friction, initial slips and the [forcing] table (rough tracks, forced oscillators)."""
    slips = [_number(entry, "slip", f"bodies[{n}]", default="0") for n, entry in enumerate(bodies_data, start=1)]
    forcing = None
    table = _table(data, "forcing", required=False)
    if table:
        _no_unknown(table, FORCING_KEYS, "forcing")
        kind = table.get("kind", "force")
        if not isinstance(kind, str):
            raise SceneError("forcing.kind", "must be a string: force | base")
        forcing = Forcing.make(
            kind, _number(table, "amplitude", "forcing", required=True),
            _number(table, "frequency", "forcing", required=True), _number(table, "phase", "forcing", default="0"),
            _number(table, "direction", "forcing", default="0"), table.get("bodies"), n_bodies=len(bodies_data))
    return {"static_friction": _number(track_table, "static_friction", "track"), "slip": slips, "forcing": forcing}


def _frame(table: dict) -> Frame:
    _no_unknown(table, FRAME_KEYS, "frame")
    return Frame.make(_number(table, "omega", "frame", default="0"), _number(table, "axis_x", "frame", default="0"))


def _path_track(table: dict):
    kind = table["type"]
    _no_unknown(table, PATH_TRACK_KEYS[kind], "track")
    if kind == "curve":
        return CurveTrack.make(table.get("y"), _number(table, "x_min", "track", required=True),
                               _number(table, "x_max", "track", required=True))
    if kind == "parametric":
        return ParametricTrack.make(table.get("x"), table.get("y"), _number(table, "u_min", "track", required=True),
                                    _number(table, "u_max", "track", required=True))
    if kind == "three_arcs":
        return ThreeArcTrack.make(_number(table, "radius", "track", required=True),
                                        _number(table, "hump_radius", "track", required=True),
                                        _number(table, "beta", "track", default="0"))
    segments_data = table.get("segments")
    if not isinstance(segments_data, list) or not all(isinstance(x, dict) for x in segments_data):
        raise SceneError("track.segments", "must be an array of tables ([[track.segments]])")
    segments = []
    for n, entry in enumerate(segments_data, start=1):
        where = f"track.segments[{n}]"
        seg_kind = entry.get("kind")
        if not isinstance(seg_kind, str) or seg_kind not in SEGMENT_KEYS:  # (a list is unhashable: found by fuzz)
            raise SceneError(f"{where}.kind", f"must be arc or line, got {seg_kind!r}")
        _no_unknown(entry, SEGMENT_KEYS[seg_kind], where)
        if seg_kind == "line":
            segments.append(Segment("line", angle=to_mpf(_number(entry, "angle", where, required=True)),
                                    length=to_mpf(_number(entry, "length", where, required=True))))
        else:
            side = entry.get("side")
            if side not in ("concave", "convex"):
                raise SceneError(f"{where}.side", f"must be concave or convex, got {side!r}")
            segments.append(Segment("arc", radius=to_mpf(_number(entry, "radius", where, required=True)), side=side,
                                    start=to_mpf(_number(entry, "start", where, required=True)),
                                    end=to_mpf(_number(entry, "end", where, required=True))))
    return ArcChainTrack.make(segments, _number(table, "start_x", "track", default="0"),
                              _number(table, "start_y", "track", default="0"))


def _path_scene(data: dict, track_table: dict, name: str, g) -> Scene:
    track = _path_track(track_table)
    frame = _frame(_table(data, "frame", required=False))
    kind = "curve" if isinstance(track, CurveTrack) else "parametric" if isinstance(track, ParametricTrack) else "arcs"
    bodies_data = _bodies_list(data)
    bodies, qs, dqs = [], [], []
    for n, entry in enumerate(bodies_data, start=1):
        field = f"bodies[{n}]"
        _no_unknown(entry, PATH_BODY_KEYS[kind], field)
        body = _make_body(entry, field)
        track.check_body(body, field)
        if kind in ("curve", "parametric"):
            c = track.coordinate
            q = _number(entry, c, field, required=True)
            dq = _number(entry, f"d{c}", field, default="0")
        elif "segment" in entry:
            if "s" in entry or "ds" in entry:
                raise SceneError(f"{field}.segment", "give s (and ds) or segment and angle (and dangle), not both")
            segment = entry["segment"]
            if isinstance(segment, bool) or not isinstance(segment, int):
                raise SceneError(f"{field}.segment", f"must be a whole number, got {segment!r}")
            q = track.coordinate_of(body, segment, _number(entry, "angle", field, required=True), field)
            with workprec():
                dq = to_mpf(_number(entry, "dangle", field, default="0")) * track.rate_scale(body, segment)
        else:
            if "angle" in entry or "dangle" in entry:
                raise SceneError(f"{field}.angle", "angle needs segment")
            q = _number(entry, "s", field, required=True)
            dq = _number(entry, "ds", field, default="0")
        bodies.append(body)
        qs.append(q)
        dqs.append(dq)
    law, policy, settings = _collision_and_run(data)
    return Scene.make(track, bodies, qs, dqs, law=law,
                      limiter_restitution=_number(track_table, "limiter_restitution", "track"),
                      frame=frame, g=g, run=settings, name=name, on_inconsistent=policy,
                      simultaneous=_simultaneous(data),
                      track_sides=_sides(track_table), friction=_number(track_table, "friction", "track"),
                      **_rough(data, track_table, bodies_data))


def _sides(table: dict) -> str:
    sides = table.get("sides", "two")
    if not isinstance(sides, str):
        raise SceneError("track.sides", "must be a string: one | two")
    return sides


def _simultaneous(data: dict) -> str:
    """[collision] simultaneous: "sequential" (default) | "impulses" (checked by Scene.make)."""
    value = _table(data, "collision", required=False).get("simultaneous", "sequential")
    if not isinstance(value, str):
        raise SceneError("collision.simultaneous", "must be a string: sequential | impulses")
    return value


def _collision_and_run(data: dict):
    """The [collision] and [run] tables, shared by every track type: (law, policy, RunSettings)."""
    collision = _table(data, "collision", required=False)
    _no_unknown(collision, COLLISION_KEYS, "collision")
    law_name = collision.get("law", "hedrih")
    if not isinstance(law_name, str):
        raise SceneError("collision.law", "must be a string")
    law = make_law(law_name, _number(collision, "restitution", "collision", default="1"))
    policy = collision.get("on_inconsistent", "newton")
    if not isinstance(policy, str):
        raise SceneError("collision.on_inconsistent", "must be a string: newton | error")
    run = _table(data, "run", required=False)
    _no_unknown(run, RUN_KEYS, "run")
    settings = RunSettings.make(_number(run, "t_end", "run", default="100"), run.get("max_collisions"))
    return law, policy, settings


def _bodies_list(data: dict) -> list:
    bodies_data = data.get("bodies")
    if bodies_data is None:
        raise SceneError("bodies", "missing: give at least one [[bodies]] table")
    if not isinstance(bodies_data, list) or not all(isinstance(b, dict) for b in bodies_data):
        raise SceneError("bodies", "must be an array of tables ([[bodies]])")
    if not bodies_data:
        raise SceneError("bodies", "at least one body is required")
    return bodies_data


def _track(table: dict) -> CircleTrack:
    _no_unknown(table, TRACK_KEYS, "track")
    kind = table.get("type")
    if kind is None:
        raise SceneError("track.type", f"missing: expected one of {' | '.join(TRACK_TYPES)}")
    if kind not in TRACK_TYPES:
        raise SceneError("track.type", f"unknown track type {kind!r}; expected one of {' | '.join(TRACK_TYPES)}")
    return CircleTrack.of_radius(_number(table, "radius", "track", required=True))


def _body(entry: dict, field: str, track: CircleTrack):
    _no_unknown(entry, BODY_KEYS, field)
    body = _make_body(entry, field)
    track.check_body(body, field)
    phi = _number(entry, "phi", field, required=True)
    if "dphi" in entry and "omega" in entry:
        raise SceneError(f"{field}.omega", "give dphi or omega, not both")
    if "omega" in entry:
        if body.is_particle:
            raise SceneError(f"{field}.omega", "a particle does not roll: give dphi")
        omega = _number(entry, "omega", field)
        with workprec():
            dphi = to_mpf(omega) / track.rolling_ratio(body)  # omega_P = (R - r)/r dphi (eq. 23)
    else:
        dphi = _number(entry, "dphi", field, default="0")  # at rest, as on every other track (acceptance test)
    return body, phi, dphi


def _make_body(entry: dict, field: str) -> Body:
    radius = _number(entry, "radius", field, required=("shape" not in entry or entry.get("shape") != "particle"), default="0")
    mass = _number(entry, "mass", field)
    density = _number(entry, "density", field)
    if "shape" in entry and "kappa" in entry:
        raise SceneError(f"{field}.kappa", "give shape or kappa, not both")
    if "kappa" in entry:
        body = Body.with_kappa(_number(entry, "kappa", field), radius, mass=mass, field=field)
        if density is not None:
            raise SceneError(f"{field}.density", "a body given by kappa has no shape to fill: give mass")
    else:
        shape = entry.get("shape")
        if shape is None:
            raise SceneError(f"{field}.shape", "missing: give shape (solid_sphere | hollow_sphere | disk | ring | particle) or kappa")
        if not isinstance(shape, str):
            raise SceneError(f"{field}.shape", "must be a string")
        body = Body.of_shape(parse_shape(shape, f"{field}.shape"), radius, mass=mass, density=density, field=field)
    return body


def _table(data: dict, key: str, *, required: bool) -> dict:
    value = data.get(key)
    if value is None:
        if required:
            raise SceneError(key, f"missing: add a [{key}] table")
        return {}
    if not isinstance(value, dict):
        raise SceneError(key, f"must be a table ([{key}])")
    return value


def _number(table: dict, key: str, prefix: str, *, required: bool = False, default=None):
    field = f"{prefix}.{key}" if prefix else key
    if key not in table:
        if required:
            raise SceneError(field, "missing: a number is required")
        return default
    value = table[key]
    if not is_number(value):
        raise SceneError(field, f"must be a number, got {value!r}")
    if not is_finite(value):
        raise SceneError(field, f"must be a finite number, got {value}")
    return value


def _no_unknown(table: dict, allowed: set, prefix: str) -> None:
    for key in table:
        if key not in allowed:
            where = f"{prefix}.{key}" if prefix else key
            raise SceneError(where, f"unknown key; allowed here: {', '.join(sorted(allowed))}")
