"""Table scenes in TOML: ``[track] type = "table"`` (issue 14; see README, "Billiards").

```toml
[track]
type = "table"
boundary = "ellipse"          # ellipse (a, b) | rectangle (width, height) | polygon (vertices) | circle (radius)
a = 2.0
b = 1.0
cushion_model = "rolling"     # rolling | slide
cushion_restitution = 1.0
friction = 0.2                # ball-cloth sliding friction (slide models)

[[bodies]]
shape = "solid_sphere"        # or kappa; particle = the point billiard
radius = 0.1
mass = 0.17
x = 0.3
y = -0.2
vx = 1.0                      # rolling unless the spin wx, wy (rad/s) is given
vy = 0.7

[collision]
law = "hedrih"                # hedrih | newton | slide | mirror
restitution = 1.0
simultaneous = "sequential"   # sequential | impulses
```
"""

from __future__ import annotations

from ..errors import SceneError
from ..model._numbers import to_mpf
from ..model.scene import STANDARD_GRAVITY, RunSettings
from ..model.table import (BOUNDARY_KEYS, CircleBoundary, EllipseBoundary, PolygonBoundary, RectangleBoundary,
                           TableBall, TableScene)

TABLE_TRACK_KEYS = {"type", "boundary", "cushion_model", "cushion_restitution", "friction"} | {
    key for keys in BOUNDARY_KEYS.values() for key in keys}
TABLE_BODY_KEYS = {"shape", "kappa", "radius", "mass", "density", "x", "y", "vx", "vy", "wx", "wy"}
TABLE_COLLISION_KEYS = {"law", "restitution", "simultaneous"}
#: ("sweep": the [sweep] table of `heyroll sweep`, as in scene_file.TOP_KEYS: `run` ignores it)
TABLE_TOP_KEYS = {"name", "g", "track", "bodies", "collision", "run", "sweep"}


def table_scene_from_dict(data: dict, name: str) -> TableScene:
    from .scene_file import RUN_KEYS, _bodies_list, _make_body, _no_unknown, _number, _table

    _no_unknown(data, TABLE_TOP_KEYS, "")
    track = data["track"]
    _no_unknown(track, TABLE_TRACK_KEYS, "track")
    boundary = _boundary(track)
    collision = _table(data, "collision", required=False)
    _no_unknown(collision, TABLE_COLLISION_KEYS, "collision")
    for key in ("law", "simultaneous"):
        if key in collision and not isinstance(collision[key], str):
            raise SceneError(f"collision.{key}", "must be a string")
    cushion_model = track.get("cushion_model", "rolling")
    if not isinstance(cushion_model, str):
        raise SceneError("track.cushion_model", "must be a string: rolling | slide")
    balls = []
    for n, entry in enumerate(_bodies_list(data), start=1):
        field = f"bodies[{n}]"
        _no_unknown(entry, TABLE_BODY_KEYS, field)
        body = _make_body(entry, field)
        spin = None
        if "wx" in entry or "wy" in entry:
            spin = (_number(entry, "wx", field, default="0"), _number(entry, "wy", field, default="0"))
        balls.append(TableBall.make(
            body, _number(entry, "x", field, required=True), _number(entry, "y", field, required=True),
            _number(entry, "vx", field, default="0"), _number(entry, "vy", field, default="0"), spin, field))
    run = _table(data, "run", required=False)
    _no_unknown(run, RUN_KEYS, "run")
    settings = RunSettings.make(_number(run, "t_end", "run", default="100"), run.get("max_collisions"))
    return TableScene.make(
        boundary, balls, law=collision.get("law", "hedrih"),
        restitution=_number(collision, "restitution", "collision", default="1"),
        cushion_model=cushion_model,
        cushion_restitution=_number(track, "cushion_restitution", "track", default="1"),
        friction=_number(track, "friction", "track", default="0.2"),
        simultaneous=collision.get("simultaneous", "sequential"),
        g=_number(data, "g", "", default=STANDARD_GRAVITY), run=settings, name=name,
    )


def _boundary(track: dict):
    from .scene_file import _number

    kind = track.get("boundary")
    if kind is None:
        raise SceneError("track.boundary", f"missing: give one of {' | '.join(BOUNDARY_KEYS)}")
    if not isinstance(kind, str) or kind not in BOUNDARY_KEYS:
        raise SceneError("track.boundary", f"unknown boundary {kind!r}; expected one of {' | '.join(BOUNDARY_KEYS)}")
    for other, keys in BOUNDARY_KEYS.items():
        for key in keys:
            if key in track and key not in BOUNDARY_KEYS[kind]:
                raise SceneError(f"track.{key}", f"not a key of {'an' if kind[0] in 'aeiou' else 'a'} {kind} boundary (it takes "
                                                 f"{', '.join(BOUNDARY_KEYS[kind])})")
    if kind == "polygon":
        vertices = track.get("vertices")
        if not isinstance(vertices, list) or not all(isinstance(v, list) and len(v) == 2 for v in vertices):
            raise SceneError("track.vertices", "must be an array of [x, y] pairs")
        points = []
        for k, (x, y) in enumerate(vertices, start=1):
            table = {"x": x, "y": y}
            points.append((to_mpf(_number(table, "x", f"track.vertices[{k}]")),
                           to_mpf(_number(table, "y", f"track.vertices[{k}]"))))
        return PolygonBoundary.make(points)
    values = {}
    for key in BOUNDARY_KEYS[kind]:
        value = to_mpf(_number(track, key, "track", required=True))
        if not value > 0:
            raise SceneError(f"track.{key}", f"must be > 0, got {track[key]}")
        values[key] = value
    if kind == "ellipse":
        return EllipseBoundary(values["a"], values["b"])
    if kind == "rectangle":
        return RectangleBoundary.of_size(values["width"], values["height"])
    return CircleBoundary(values["radius"])
