"""The result of a run: status, message, collision records and tables."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from ..model.laws import collision_impulse, kinetic_energy_change
from ..model.scene import ContactPair, Scene
from ..model.tracks import mechanical_energy
from .precision import Precision


class Status(str, Enum):
    """How a run ended. ``completed`` and ``max_collisions`` are successes."""

    COMPLETED = "completed"
    MAX_COLLISIONS = "max_collisions"
    CONTACT = "contact"
    INCONSISTENT = "inconsistent_collision"
    INTERRUPTED = "interrupted"
    LEFT_TRACK = "left_track"
    SLIP = "slip"
    OVERLAP = "overlap"
    FAILED = "failed"

    @property
    def success(self) -> bool:
        return self in (Status.COMPLETED, Status.MAX_COLLISIONS)


#: Columns of the collision table, in order (see README, "Outputs").
TABLE_COLUMNS = (
    "n", "t", "i", "j", "phi_i", "phi_j",
    "omega_i_before", "omega_j_before", "omega_i_after", "omega_j_after",
    "energy_before", "energy_after",
    "dphi_i_before", "dphi_j_before", "dphi_i_after", "dphi_j_after",
    "law_impulse", "law_energy_change", "law_flag",
)
INTEGER_COLUMNS = ("n", "i", "j", "law_flag")

#: law_flag values: which law resolved the collision.
LAW_FLAGS = {0: "the scene's law", 1: "fallback: Newton's law on the gap rate (the scene's law left the bodies approaching)",
             2: "Newton's law on psi' between units (a cluster in persistent contact took part)"}


@dataclass(frozen=True)
class BodyConstants:
    """Per-body numbers for vectorized post-processing, in one number type."""

    generalized_mass: np.ndarray
    weight_moment: np.ndarray
    rolling_ratio: np.ndarray  # (R - r)/r, NaN for particles


def body_constants(scene: Scene, number=float) -> BodyConstants:
    """The constants rounded by ``number`` (float, or a Precision's ``number`` for quad/MPFR)."""
    tr, g = scene.track, scene.g
    nan = number(float("nan"))
    return BodyConstants(
        generalized_mass=np.array([number(tr.generalized_mass(b)) for b in scene.bodies]),
        weight_moment=np.array([number(tr.weight_moment(b, g)) for b in scene.bodies]),
        rolling_ratio=np.array([nan if b.is_particle else number(tr.rolling_ratio(b)) for b in scene.bodies]),
    )


def body_energies(constants: BodyConstants, states: np.ndarray) -> np.ndarray:
    """Mechanical energy of every body (columns) for each state row (eq. 26).

    Works in the number type of ``states`` and ``constants`` (float64, or
    heyoka's real128 / real arrays, whose numpy ufuncs keep their precision).
    """
    states = np.atleast_2d(np.asarray(states))
    n = constants.generalized_mass.size
    return mechanical_energy(constants.generalized_mass, constants.weight_moment, states[:, :n], states[:, n:], np.sin)


def build_collision_table(
    scene: Scene, pairs, precision: Precision, times, pair_numbers, states_before, states_after,
    flags=None, *, first_number: int = 1, native: bool = False,
) -> np.ndarray:
    """The collision table (columns TABLE_COLUMNS) of raw collision records.

    ``states_before[n]`` / ``states_after[n]`` are full states
    [phi_1..phi_N, dphi_1..dphi_N]; ``pair_numbers[n]`` indexes ``pairs``;
    rows are numbered from ``first_number``.
    """
    native = native and precision.name != "double"
    number = precision.number if native else float
    as_array = np.asarray if native else (lambda x: np.asarray(x, dtype=float))
    n = len(times)
    float_type = object if native else np.float64
    dtype = [(c, np.int64 if c in INTEGER_COLUMNS else float_type) for c in TABLE_COLUMNS]
    table = np.zeros(n, dtype=dtype)
    if n == 0:
        return table
    nb = len(scene.bodies)
    before, after = as_array(states_before), as_array(states_after)
    i = np.array([p.i for p in pairs], dtype=np.int64)[pair_numbers]
    j = np.array([p.j for p in pairs], dtype=np.int64)[pair_numbers]
    rows = np.arange(n)
    c = body_constants(scene, number)
    table["n"] = rows + first_number
    table["t"] = as_array(times)
    table["i"], table["j"] = i + 1, j + 1
    table["phi_i"], table["phi_j"] = before[rows, i], before[rows, j]
    for side, idx in (("i", i), ("j", j)):
        table[f"dphi_{side}_before"] = before[rows, nb + idx]
        table[f"dphi_{side}_after"] = after[rows, nb + idx]
        table[f"omega_{side}_before"] = c.rolling_ratio[idx] * before[rows, nb + idx]
        table[f"omega_{side}_after"] = c.rolling_ratio[idx] * after[rows, nb + idx]
    table["energy_before"] = body_energies(c, before).sum(axis=1)
    table["energy_after"] = body_energies(c, after).sum(axis=1)
    impulse, change = _law_quantities(scene, i, j, before[rows, nb + i], before[rows, nb + j], number)
    table["law_impulse"], table["law_energy_change"] = impulse, change
    table["law_flag"] = 0 if flags is None else flags
    return table


def _law_quantities(scene: Scene, i, j, dphi_i, dphi_j, number=float):
    """Moment of the collision impulse (eq. 12) and kinetic-energy change (eq. 15)."""
    law, tr, bodies = scene.law, scene.track, scene.bodies
    k = number(law.restitution)
    impulse = np.empty(i.size, dtype=dphi_i.dtype)
    change = np.empty(i.size, dtype=dphi_i.dtype)
    for pair in {(a, b) for a, b in zip(i.tolist(), j.tolist())}:
        mask = (i == pair[0]) & (j == pair[1])
        vi, vj = law.variables(tr, bodies[pair[0]]), law.variables(tr, bodies[pair[1]])
        mi, mj = number(vi.inertia), number(vj.inertia)
        du = number(vi.scale) * dphi_i[mask] - number(vj.scale) * dphi_j[mask]
        impulse[mask] = collision_impulse(mi, mj, k, du)
        change[mask] = kinetic_energy_change(mi, mj, k, du)
    return impulse, change


@dataclass(frozen=True)
class SimulationResult:
    """What :func:`heyroll.simulate` returns.

    ``states_before[n]`` / ``states_after[n]`` hold the full state
    [phi_1..phi_N, dphi_1..dphi_N] just before / after collision n (0-based);
    ``pair_numbers[n]`` indexes ``pairs``. Use :meth:`collision_table` for the
    table with bodies numbered from 1.
    """

    scene: Scene
    status: Status
    message: str
    precision: Precision
    t_final: float
    initial_state: np.ndarray
    final_state: np.ndarray
    times: np.ndarray
    pair_numbers: np.ndarray
    pairs: tuple[ContactPair, ...]
    states_before: np.ndarray
    states_after: np.ndarray
    wall_time_s: float
    steps: int = 0
    settings: dict = field(default_factory=dict)
    #: Collisions in the whole run; None: all are in memory (times.size).
    total_collisions: int | None = None
    #: Where the full table was streamed to (None: not streamed).
    table_file: str | None = None
    #: Per kept collision: 0 the scene's law, 1 the fallback law, 2 a cluster collision (LAW_FLAGS).
    law_flags: np.ndarray | None = None
    #: Persistent contacts: dicts with i, j (1-based), t_start, t_end (and open: True if still on at the end).
    contact_intervals: tuple = ()
    #: Mode changes (ModeChange: t, clusters, full state), the first at t = 0.
    mode_changes: tuple = ()

    @property
    def success(self) -> bool:
        return self.status.success

    @property
    def n_collisions(self) -> int:
        """Collisions in the whole run (streamed ones included)."""
        return int(self.times.size) if self.total_collisions is None else self.total_collisions

    @property
    def kept_collisions(self) -> int:
        """Collisions whose records are in memory (all, unless the table was streamed)."""
        return int(self.times.size)

    @property
    def n_bodies(self) -> int:
        return len(self.scene.bodies)

    def constants(self) -> BodyConstants:
        return body_constants(self.scene)

    def energy(self, state) -> float:
        return float(body_energies(self.constants(), state).sum())

    @property
    def energy_initial(self) -> float:
        return self.energy(self.initial_state)

    @property
    def energy_final(self) -> float:
        return self.energy(self.final_state)

    def collision_table(self, native: bool = False) -> np.ndarray:
        """One row per collision kept in memory, as a numpy structured array.

        Columns TABLE_COLUMNS. Every float column is float64 by default; with
        ``native=True`` a quad or MPFR run keeps its own number type (object
        columns of heyoka real128 / real), so its table can be written in full
        digits. A run streamed to a file keeps only its first collisions here
        (``kept_collisions``); the file has them all.
        """
        return build_collision_table(
            self.scene, self.pairs, self.precision, self.times, self.pair_numbers,
            self.states_before, self.states_after, self.law_flags, native=native,
        )

    def summary(self) -> dict:
        """The run in a JSON-ready dictionary (see README, "Outputs")."""
        nb = self.n_bodies
        final = np.asarray(self.final_state, dtype=float)
        return {
            "status": self.status.value,
            "message": self.message,
            "collisions": self.n_collisions,
            "t_final": float(self.t_final),
            "energy_initial": self.energy_initial,
            "energy_final": self.energy_final,
            "final_state": [
                {"body": k + 1, "phi": float(final[k]), "dphi": float(final[nb + k])} for k in range(nb)
            ],
            "wall_time_s": self.wall_time_s,
            "steps": self.steps,
            "precision": self.precision.name,
            "significant_digits": self.precision.digits,
            "t_final_text": self.precision.format(self.t_final),
            "law": self.scene.law.name,
            "restitution": float(self.scene.law.restitution),
            "contact_intervals": list(self.contact_intervals),
            **self.settings,
        }
