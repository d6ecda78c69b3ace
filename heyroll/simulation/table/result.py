"""The result of a table run: status and message, the impact table, paths for figures."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...model.table import TableScene
from ..precision import Precision
from ..result import Status

#: Columns of a table run's collisions.csv (issue 14): j = 0 for a cushion impact (its j columns
#: are then empty), boundary_s and reflection_angle empty for a ball-ball impact.
IMPACT_COLUMNS = (
    "n", "t", "i", "j", "x_i", "y_i", "vx_i_before", "vy_i_before", "vx_i_after", "vy_i_after",
    "x_j", "y_j", "vx_j_before", "vy_j_before", "vx_j_after", "vy_j_after", "energy_before", "energy_after",
    "boundary_s", "reflection_angle", "law_flag",
)
INTEGER_COLUMNS = ("n", "i", "j", "law_flag")
#: Columns computed in float64 from the run's numbers, whatever the precision (17 digits in the CSV).
DERIVED_COLUMNS = ("boundary_s", "reflection_angle")
#: Raw record of an impact (run-type numbers): the table's columns from t to energy_after, then the
#: contact point on the boundary and the cushion's outward normal (nan for a ball-ball impact), the flag.
RECORD_FIELDS = IMPACT_COLUMNS[1:18] + ("px", "py", "nx", "ny", "law_flag")


def impact_table(scene: TableScene, records: list, precision: Precision, first_number: int = 1,
                 native: bool = False) -> np.ndarray:
    """Records as a structured array (float64; object columns in the run's own type with ``native``
    on a quad or MPFR run). Empty cells are nan (float64) or None (object)."""
    wide = native and precision.name != "double"
    number = object if wide else np.float64
    # boundary_s and reflection_angle are derived in float64 (for figures and maps) in every precision
    dtype = [(name, np.int64 if name in INTEGER_COLUMNS else np.float64 if name in DERIVED_COLUMNS else number)
             for name in IMPACT_COLUMNS]
    table = np.zeros(len(records), dtype=dtype)
    if not records:
        return table
    table["n"] = np.arange(first_number, first_number + len(records))
    cols = list(zip(*records))
    index = {name: k for k, name in enumerate(RECORD_FIELDS)}
    for name in IMPACT_COLUMNS[1:18]:
        values = cols[index[name]]
        if name in ("i", "j"):
            table[name] = [int(v) for v in values]
        elif wide:
            table[name] = list(values)
        else:
            table[name] = [float(v) for v in values]
    table["law_flag"] = [int(v) for v in cols[index["law_flag"]]]
    px = np.array([float(v) for v in cols[index["px"]]])
    py = np.array([float(v) for v in cols[index["py"]]])
    nx = np.array([float(v) for v in cols[index["nx"]]])
    ny = np.array([float(v) for v in cols[index["ny"]]])
    cushion = table["j"] == 0
    s = np.full(len(records), np.nan)
    angle = np.full(len(records), np.nan)
    if cushion.any():
        s[cushion] = scene.boundary.arc_length(px[cushion], py[cushion])
        vx = np.array([float(v) for v in cols[index["vx_i_after"]]])[cushion]
        vy = np.array([float(v) for v in cols[index["vy_i_after"]]])[cushion]
        # angle of the outgoing velocity from the inward normal, > 0 toward the counter-clockwise tangent
        angle[cushion] = np.arctan2(vx * -ny[cushion] + vy * nx[cushion], -(vx * nx[cushion] + vy * ny[cushion]))
        # a ball at rest after it (k = 0 head-on, pinned in a corner) has no angle (atan2(0, -0) gave pi)
        angle[np.flatnonzero(cushion)[(vx == 0) & (vy == 0)]] = np.nan
    empty = None if wide else np.nan
    for name in ("x_j", "y_j", "vx_j_before", "vy_j_before", "vx_j_after", "vy_j_after"):
        if wide:
            column = table[name]
            column[cushion] = empty
        else:
            table[name][cushion] = np.nan
    table["boundary_s"] = s
    table["reflection_angle"] = angle
    return table


@dataclass
class TableResult:
    """How a table run ended (``status``, ``message``) and what it found.

    ``records`` are the impacts kept in memory (all of them without a sink;
    the first chunk with one); ``n_collisions`` counts every impact.
    ``paths``: (t, state, accelerations, riding balls) at the start of each
    piece of motion (up to ``MAX_PATH_PIECES``), for figures: between events
    every ball moves with constant acceleration, or rides the cushion.
    ``riding_final``: the balls (1-based) riding the cushion at the end.
    """

    scene: TableScene
    status: Status
    message: str
    precision: Precision
    t_final: object
    state_initial: list
    state_final: list
    energy_initial: float
    energy_final: float
    n_collisions: int
    n_cushion: int
    n_rerolls: int
    records: list
    paths: list = field(default_factory=list)
    wall_time_s: float = 0.0
    settings: dict = field(default_factory=dict)
    steps: int = 0
    riding_final: tuple = ()

    kind = "table"

    @property
    def success(self) -> bool:
        return self.status.success

    @property
    def n_bodies(self) -> int:
        return self.scene.n_bodies

    def collision_table(self, native: bool = False) -> np.ndarray:
        return impact_table(self.scene, self.records, self.precision, 1, native)

    def summary(self) -> dict:
        n = self.scene.n_bodies
        final = [float(v) for v in self.state_final]
        return {
            "status": self.status.value,
            "status_meaning": self.status.meaning,
            "message": self.message,
            "track": "table",
            "boundary": self.scene.boundary.kind,
            "collisions": self.n_collisions,
            "cushion_impacts": self.n_cushion,
            "ball_collisions": self.n_collisions - self.n_cushion,
            "rerolls": self.n_rerolls,
            "t_final": float(self.t_final),
            "t_final_text": self.precision.format(self.t_final),
            "energy_initial": self.energy_initial,
            "energy_final": self.energy_final,
            "steps": self.steps,
            "precision": self.precision.name,
            "significant_digits": self.precision.digits,
            "law": self.scene.law.name,
            "restitution": float(self.scene.law.restitution),
            "cushion_model": self.scene.cushion.name,
            "cushion_restitution": float(self.scene.cushion.restitution),
            "friction": float(self.scene.friction),
            "simultaneous": self.scene.simultaneous,
            "final_state": [
                {"body": k + 1, "x": final[6 * k], "y": final[6 * k + 1], "vx": final[6 * k + 2],
                 "vy": final[6 * k + 3], "slip_x": final[6 * k + 4], "slip_y": final[6 * k + 5]}
                for k in range(n)
            ],
            # the run's own digits (long, quad, mp), as t_final_text
            "final_state_text": [
                dict(body=k + 1, **{name: self.precision.format(self.state_final[6 * k + m])
                                    for m, name in enumerate(("x", "y", "vx", "vy", "slip_x", "slip_y"))})
                for k in range(n)
            ],
            "riding_final": list(self.riding_final),
            "wall_time_s": self.wall_time_s,
            "settings": self.settings,
        }
