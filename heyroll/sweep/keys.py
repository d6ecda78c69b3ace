"""KEY paths: which numeric scene field a sweep varies, named as in the scene file.

``collision.restitution``, ``bodies[2].mass``, ``frame.omega``, ``forcing.amplitude``, ``g``,
``track.segments[3].radius``: a table (or an array of tables with a 1-based
index, bodies numbered 1..N as everywhere) and a field. A KEY is checked
against the scene file's own key sets (heyroll.interfaces.scene_file), so it
names exactly the fields a scene file may hold; a point's value is written
into a copy of the parsed TOML and the scene is built by the normal loader,
so every point gets the normal validation (issue 16).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ..interfaces import scene_file as sf
from .errors import SweepKeyError

#: Scene-file fields that hold text or tables, never a number.
NOT_NUMERIC = {"name", "type", "sides", "y", "kind", "side", "shape", "law", "on_inconsistent", "simultaneous",
               "segments", "sweep", "track", "bodies", "collision", "run", "frame", "forcing"}
#: A table scene's fields that hold text or lists (heyroll.interfaces.table_file).
TABLE_TEXT = {"boundary", "cushion_model", "vertices", "simultaneous"}
#: Numeric fields that take whole numbers only.
WHOLE_NUMBERS = {"segment", "max_collisions"}
#: Two ways of giving one quantity: a point that sets one drops the other from its copy of the
#: scene (varying ``bodies[1].mass`` of a body given by density gives it that mass).
ALTERNATIVES = {"mass": "density", "density": "mass", "dphi": "omega", "omega": "dphi",
                # a body's kappa stands for its shape (review: every point was "give shape or kappa, not both")
                "kappa": "shape"}

_PART = re.compile(r"([A-Za-z_]+)(?:\[(\d+)\])?$")


@dataclass(frozen=True)
class Key:
    """A parsed KEY: ``path`` is ((name, index or None), ...), the index 1-based."""

    text: str
    path: tuple

    @property
    def field(self) -> str:
        """The last name: ``mass`` for ``bodies[2].mass``."""
        return self.path[-1][0]

    @property
    def whole(self) -> bool:
        return self.field in WHOLE_NUMBERS


def parse_key(text: str, data: dict) -> Key:
    """Check ``text`` against the parsed scene ``data``; raise SweepKeyError naming it if it is no numeric field."""
    if not isinstance(text, str) or not text.strip():
        raise SweepKeyError(str(text), "an empty KEY: name a numeric scene field, e.g. collision.restitution")
    text = text.strip()
    parts = []
    for part in text.split("."):
        match = _PART.match(part)
        if match is None:
            raise SweepKeyError(text, f"not a KEY (table.field, bodies[N].field): bad part {part!r}")
        parts.append((match.group(1), None if match.group(2) is None else int(match.group(2))))
    key = Key(text, tuple(parts))
    _check(key, data)
    return key


def _check(key: Key, data: dict) -> None:
    track = data.get("track") if isinstance(data.get("track"), dict) else {}
    kind = track.get("type") if isinstance(track.get("type"), str) else "circle"  # the loader names a bad type
    path = key.path

    def unknown(rule: str):
        raise SweepKeyError(key.text, f"unknown sweep key: {rule}")

    # On a table a body's y is its centre's ordinate (on a curve track, y is the curve's expression).
    not_numeric = (NOT_NUMERIC - {"y"}) | TABLE_TEXT if kind == "table" else NOT_NUMERIC

    def numeric(name: str, allowed: set, where: str):
        if name not in allowed or name in not_numeric:
            numbers = sorted(k for k in allowed if k not in not_numeric)
            unknown(f"{where} has no numeric field {name!r}; numeric fields there: {', '.join(numbers)}")

    head, index = path[0]
    if kind == "table":
        _check_table(key, data, unknown, numeric)
        return
    if head == "bodies":
        if index is None or len(path) != 2:
            unknown("name a body and a field, e.g. bodies[1].mass (bodies numbered from 1)")
        bodies = data.get("bodies") if isinstance(data.get("bodies"), list) else []
        if not 1 <= index <= len(bodies):
            unknown(f"the scene has {len(bodies)} bodies, numbered 1..{len(bodies)}")
        allowed = (sf.BODY_KEYS if kind not in sf.PATH_TRACK_KEYS
                   else sf.PATH_BODY_KEYS.get(kind, sf.PATH_BODY_KEYS["arcs"]))  # three_arcs: as arcs
        numeric(path[1][0], allowed, f"bodies[{index}] on a {kind} track")
        if path[1][1] is not None:
            unknown(f"{path[1][0]} is not an array")
        return
    if index is not None:
        unknown(f"{head} is not an array of tables")
    if len(path) == 1:
        numeric(head, sf.TOP_KEYS, "the top level")
        return
    if head == "track" and path[1][0] == "segments":
        segments = track.get("segments") if isinstance(track.get("segments"), list) else []
        n = path[1][1]
        if kind != "arcs" or n is None or len(path) != 3:
            unknown("track.segments[N].field needs an arcs track and a segment number")
        if not 1 <= n <= len(segments) or not isinstance(segments[n - 1], dict):
            unknown(f"the track has {len(segments)} segments, numbered 1..{len(segments)}")
        seg_kind = segments[n - 1].get("kind")
        numeric(path[2][0], sf.SEGMENT_KEYS.get(seg_kind, set()), f"track.segments[{n}] ({seg_kind})")
        return
    tables = {
        "track": sf.PATH_TRACK_KEYS.get(kind, sf.TRACK_KEYS),
        "frame": sf.FRAME_KEYS,
        "collision": sf.COLLISION_KEYS,
        "run": sf.RUN_KEYS,
        "forcing": sf.FORCING_KEYS,
    }
    if head not in tables:
        unknown(f"no table {head!r} with numeric fields; tables: {', '.join(tables)}, bodies[N], and g")
    if len(path) != 2:
        unknown(f"name one field of [{head}], e.g. {head}.{sorted(k for k in tables[head] if k not in NOT_NUMERIC)[0]}")
    if path[1][1] is not None:
        unknown(f"{path[1][0]} is not an array")
    numeric(path[1][0], tables[head], f"[{head}]")


def _check_table(key: Key, data: dict, unknown, numeric) -> None:
    """A KEY of a billiard table scene (heyroll.interfaces.table_file): a ball's field, the table's or
    the collision law's, or g."""
    from ..interfaces import table_file as tf

    path = key.path
    head, index = path[0]
    if head == "bodies":
        bodies = data.get("bodies") if isinstance(data.get("bodies"), list) else []
        if index is None or len(path) != 2 or not 1 <= index <= len(bodies):
            unknown(f"name a ball and a field, e.g. bodies[1].vx (the table has {len(bodies)} ball{'' if len(bodies) == 1 else 's'}, from 1)")
        numeric(path[1][0], tf.TABLE_BODY_KEYS, f"bodies[{index}] on a table")
        return
    # the track's fields of this scene's boundary only (track.radius on an ellipse was accepted and every point
    # recorded as an invalid scene: acceptance test)
    track = data.get("track") if isinstance(data.get("track"), dict) else {}
    boundary = track.get("boundary")
    own = set(tf.BOUNDARY_KEYS.get(boundary, ())) if isinstance(boundary, str) else set()
    others = {k for keys in tf.BOUNDARY_KEYS.values() for k in keys} - own
    tables = {"track": tf.TABLE_TRACK_KEYS - others, "collision": tf.TABLE_COLLISION_KEYS, "run": sf.RUN_KEYS}
    if index is not None or any(i is not None for _n, i in path[1:]):
        unknown(f"{head} is not an array")
    if len(path) == 1:
        numeric(head, tf.TABLE_TOP_KEYS, "the top level of a table scene")
    elif head not in tables or len(path) != 2:
        unknown(f"a table scene's numeric fields are in {', '.join(tables)}, bodies[N], and g")
    else:
        numeric(path[1][0], tables[head], f"[{head}] of a table scene")


def apply(data: dict, key: Key, value) -> None:
    """Write ``value`` at ``key`` in ``data`` (a point's own copy of the parsed TOML), creating a missing table."""
    node = data
    for name, index in key.path[:-1]:
        if index is None:
            node = node.setdefault(name, {})
        else:
            node = node[name][index - 1]
    field = key.field
    node[field] = value
    other = ALTERNATIVES.get(field)
    if other is not None and key.path[0][0] == "bodies":
        node.pop(other, None)


#: SI units of each numeric field, by its name ('' for a pure number).
_UNITS = {
    "g": "m/s²", "radius": "m", "hump_radius": "m", "mass": "kg", "friction": "", "restitution": "",
    "limiter_restitution": "", "kappa": "", "beta": "rad", "axis_x": "m", "start_x": "m", "start_y": "m",
    "x_min": "m", "x_max": "m", "x": "m", "dx": "m/s", "s": "m", "ds": "m/s", "phi": "rad", "dphi": "rad/s",
    "angle": "rad", "dangle": "rad/s", "length": "m", "start": "rad", "end": "rad", "t_end": "s",
    "max_collisions": "", "segment": "", "frequency": "rad/s", "phase": "rad", "direction": "rad",
    "omega": "rad/s",  # the frame's rotation or a body's rolling angular velocity
    "y": "m", "vx": "m/s", "vy": "m/s", "wx": "rad/s", "wy": "rad/s", "a": "m", "b": "m", "width": "m",
    "height": "m", "cushion_restitution": "",  # a table's balls and cushion
    "u": "", "du": "1/s",  # a parametric track's parameter (a pure number) and its rate
}
#: A body's density is per volume, area or length, by its shape (README, "Bodies").
_DENSITY = {"solid_sphere": "kg/m³", "hollow_sphere": "kg/m²", "disk": "kg/m²", "ring": "kg/m"}


def units(key: Key, data: dict) -> str:
    """SI units of ``key`` in the scene ``data`` (a density's follow the body's shape)."""
    if key.field == "density":
        return _DENSITY.get(data["bodies"][key.path[0][1] - 1].get("shape"), "")
    return _UNITS.get(key.field, "")
