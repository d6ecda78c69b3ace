"""The result of a run: status, message, collision records and tables."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from ..model.laws import collision_impulse, kinetic_energy_change
from ..model.scene import ContactPair, Scene
from ..model.table import is_table
from ..model.tracks import first_integral, mechanical_energy
from .compiled_cache import by_constants
from .precision import Precision


def counted(n: int, noun: str) -> str:
    """'1 collision', '2 collisions': counts in messages and reports, in English."""
    return f"{n} {noun}" + ("" if n == 1 else "s")


class Status(str, Enum):
    """How a run ended. ``completed``, ``max_collisions`` and ``max_events`` are successes.

    Each member carries its meaning (``meaning``) and the CLI's exit code (``exit_code``).
    """

    COMPLETED = "completed"
    MAX_COLLISIONS = "max_collisions"
    MAX_EVENTS = "max_events"
    INCONSISTENT = "inconsistent_collision"
    INTERRUPTED = "interrupted"
    LEFT_TRACK = "left_track"
    OVERLAP = "overlap"
    FAILED = "failed"

    @property
    def success(self) -> bool:
        return self in (Status.COMPLETED, Status.MAX_COLLISIONS, Status.MAX_EVENTS)

    @property
    def meaning(self) -> str:
        return _MEANINGS[self]

    @property
    def exit_code(self) -> int:
        return 0 if self.success else 130 if self is Status.INTERRUPTED else 1


_MEANINGS = {
    Status.COMPLETED: "reached t_end",
    Status.MAX_COLLISIONS: "stopped after the scene's or the run's max_collisions",
    Status.MAX_EVENTS: "stopped after max_events events (collisions, junction passages, limiter impacts, mode changes)",
    Status.INCONSISTENT: "the law's outcome would leave two bodies approaching (on_inconsistent = 'error')",
    Status.INTERRUPTED: "stopped by Ctrl-C or SIGTERM; the table holds every collision before the stop",
    Status.LEFT_TRACK: "a body would leave a one-sided track (its normal force reached 0)",
    Status.OVERLAP: "a collision was missed (the bodies overlapped by more than the overlap tolerance)",
    Status.FAILED: "the integrator could not go on",
}


#: Columns of the collision table, in order (see README, "Outputs").
TABLE_COLUMNS = (
    "n", "t", "i", "j", "q_i", "q_j",
    "omega_i_before", "omega_j_before", "omega_i_after", "omega_j_after",
    "energy_before", "energy_after",
    "dq_i_before", "dq_j_before", "dq_i_after", "dq_j_after",
    "law_impulse", "law_energy_change", "law_flag",
)

#: Columns of the passages table (junction passages and limiter impacts, see README).
PASSAGE_COLUMNS = ("n", "t", "body", "kind", "piece_from", "piece_to", "q", "dq_before", "dq_after")
INTEGER_COLUMNS = ("n", "i", "j", "law_flag")
#: Rough tracks: the table gains the friction modes of the two bodies before and after each collision.
MODE_COLUMNS = ("mode_i_before", "mode_j_before", "mode_i_after", "mode_j_after")


def table_columns(scene: Scene) -> tuple:
    """The collision table's columns for ``scene``: TABLE_COLUMNS, then MODE_COLUMNS on a rough track."""
    if is_table(scene):  # billiards (paper section 7)
        from .table.result import IMPACT_COLUMNS

        return IMPACT_COLUMNS
    return TABLE_COLUMNS + (MODE_COLUMNS if scene.rough else ())

#: Columns of the friction transitions table (rough tracks, see README).
TRANSITION_COLUMNS = ("n", "t", "body", "from", "to", "q", "dq")

#: law_flag values: which law resolved the collision.
LAW_FLAGS = {0: "the scene's law", 1: "fallback: Newton's law on the gap rate (the scene's law left the bodies approaching)",
             2: "Newton's law on the gap rate between units (a cluster in persistent contact, or a body resting on a limiter, took part)",
             3: "Newton's law with a slipping rolling body's translational inertia (rough tracks: the impulse through its centre, its spin unchanged)"}


@dataclass(frozen=True)
class BodyConstants:
    """Per-body numbers for vectorized post-processing on the circle, in one number type."""

    generalized_mass: np.ndarray
    weight_moment: np.ndarray
    rolling_ratio: np.ndarray  # (R - r)/r, NaN for particles


@by_constants()
def body_constants(scene: Scene, number=float) -> BodyConstants:
    """The circle's constants rounded by ``number`` (float, or a Precision's ``number`` for long/quad/MPFR).

    Computed once per scene constants and ``number`` (from the model's mpmath numbers: ~0.2 ms, measured,
    which every run's energy_initial and energy_final paid again); the arrays are read-only."""
    tr, g = scene.track, scene.g
    nan = number(float("nan"))
    arrays = (np.array([number(tr.generalized_mass(b)) for b in scene.bodies]),
              np.array([number(tr.weight_moment(b, g)) for b in scene.bodies]),
              np.array([nan if b.is_particle else number(tr.rolling_ratio(b)) for b in scene.bodies]))
    for a in arrays:
        a.flags.writeable = False
    return BodyConstants(*arrays)


def closed_form_energy(scene: Scene) -> bool:
    """Energies in the run's own type by eq. (26): a fixed circle. Elsewhere the first integral in float64."""
    return scene.track.linear_gap and not scene.frame.rotating


def body_energies(constants, states: np.ndarray, scene: Scene | None = None) -> np.ndarray:
    """Mechanical energy of every body (columns) for each state row.

    On a fixed circle (``constants`` a :class:`BodyConstants`) eq. (26) in the
    number type of ``states`` and ``constants`` (float64, or long double /
    real128 / real arrays, whose numpy ufuncs keep their precision); with
    ``scene`` on any other track the first integral of eq. (92), float64.
    """
    states = np.atleast_2d(np.asarray(states))
    if scene is not None and not closed_form_energy(scene):
        n = len(scene.bodies)
        q, dq = np.asarray(states[:, :n], dtype=float), np.asarray(states[:, n:], dtype=float)
        return np.stack([first_integral(scene.track, b, q[:, k], dq[:, k], scene.g, scene.frame)
                         for k, b in enumerate(scene.bodies)], axis=1)
    n = constants.generalized_mass.size
    return mechanical_energy(constants.generalized_mass, constants.weight_moment, states[:, :n], states[:, n:], np.sin)


def state_energies(scene: Scene, states, number=float) -> np.ndarray:
    """Body energies of state rows on any track (see :func:`body_energies`)."""
    if closed_form_energy(scene):
        return body_energies(body_constants(scene, number), states)
    return body_energies(None, states, scene)


def rolling_ratios(scene: Scene, q, number=float) -> np.ndarray:
    """omega_P / q' = sigma(q)/r per row and body (NaN for particles): (R - r)/r on a circle (eq. 23)."""
    q = np.atleast_2d(np.asarray(q))
    out = np.empty(q.shape, dtype=object if number is not float else float)
    for k, b in enumerate(scene.bodies):
        if b.is_particle:
            out[:, k] = number(float("nan"))
        elif scene.track.constant_metric and scene.track.linear_gap:
            out[:, k] = number(scene.track.rolling_ratio(b))
        else:
            out[:, k] = scene.track.sigma(b, np.asarray(q[:, k], dtype=float)) / float(b.radius)
    return out


def build_collision_table(
    scene: Scene, pairs, precision: Precision, times, pair_numbers, states_before, states_after,
    flags=None, *, first_number: int = 1, native: bool = False, modes=None, spins=None,
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
    if scene.rough:  # ``modes``: (n, 4) mode names, MODE_COLUMNS
        dtype += [(c, "U8") for c in MODE_COLUMNS]
    table = np.zeros(n, dtype=dtype)
    if n == 0:
        return table
    if scene.rough and modes is not None:
        modes = np.asarray(modes).reshape(n, len(MODE_COLUMNS))
        for c, name in enumerate(MODE_COLUMNS):
            table[name] = modes[:, c]
    nb = len(scene.bodies)
    before, after = as_array(states_before), as_array(states_after)
    i = np.array([p.i for p in pairs], dtype=np.int64)[pair_numbers]
    j = np.array([p.j for p in pairs], dtype=np.int64)[pair_numbers]
    rows = np.arange(n)
    ratio = rolling_ratios(scene, before[:, :nb], number)
    table["n"] = rows + first_number
    table["t"] = as_array(times)
    table["i"], table["j"] = i + 1, j + 1
    table["q_i"], table["q_j"] = before[rows, i], before[rows, j]
    for side, idx in (("i", i), ("j", j)):
        table[f"dq_{side}_before"] = before[rows, nb + idx]
        table[f"dq_{side}_after"] = after[rows, nb + idx]
        table[f"omega_{side}_before"] = ratio[rows, idx] * before[rows, nb + idx]
        table[f"omega_{side}_after"] = ratio[rows, idx] * after[rows, nb + idx]
    table["energy_before"] = state_energies(scene, before, number).sum(axis=1)
    table["energy_after"] = state_energies(scene, after, number).sum(axis=1)
    if scene.rough and spins is not None:
        # A slipping body's kinetic energy is 1/2 m v^2 + 1/2 m (kappa - 1) u^2, not the rolling
        # 1/2 kappa m v^2: the difference, for every slipping body (not only the row's two: a body sliding
        # elsewhere was left out, acceptance test), each row with its own rates, u unchanged through the
        # impacts of an instant (the spin keeps it; one u for every row of a triple impact, review).
        spins = np.asarray(spins, dtype=float).reshape(n, nb)
        for k in np.flatnonzero(~np.all(np.isnan(spins), axis=0)):
            body = scene.bodies[k]
            share = 0.5 * float(body.mass) * (float(body.kappa) - 1)
            for r in np.flatnonzero(~np.isnan(spins[:, k])):
                sigma = float(scene.track.sigma(body, float(before[r, k])))
                u = spins[r, k]
                for name, state in (("energy_before", before), ("energy_after", after)):
                    v = sigma * float(state[r, nb + k])
                    table[name][r] = table[name][r] + number(share * (u * u - v * v))
    impulse, change = _law_quantities(scene, i, j, before[rows, i], before[rows, j], before[rows, nb + i],
                                      before[rows, nb + j], number)
    table["law_impulse"], table["law_energy_change"] = impulse, change
    table["law_flag"] = 0 if flags is None else flags
    if flags is not None:  # rows another law resolved (flags 1-3): the scene's law's quantities do not apply
        other = np.asarray(flags) != 0
        if other.any():
            table["law_impulse"][other] = number(float("nan"))
            table["law_energy_change"][other] = number(float("nan"))
    return table


def _law_quantities(scene: Scene, i, j, q_i, q_j, dphi_i, dphi_j, number=float):
    """Moment of the collision impulse (eq. 12) and kinetic-energy change (eq. 15), in the law's variables
    at the metric of the contact point."""
    law, bodies = scene.law, scene.bodies
    k = number(law.restitution)
    impulse = np.empty(i.size, dtype=dphi_i.dtype)
    change = np.empty(i.size, dtype=dphi_i.dtype)
    constant = scene.track.linear_gap and scene.track.constant_metric
    for pair in {(a, b) for a, b in zip(i.tolist(), j.tolist())}:
        mask = (i == pair[0]) & (j == pair[1])
        bi, bj = bodies[pair[0]], bodies[pair[1]]
        if constant:
            vi, vj = law.variables(bi, scene.sigma(pair[0])), law.variables(bj, scene.sigma(pair[1]))
            mi, mj = number(vi.inertia), number(vj.inertia)
            ci, cj = number(vi.scale), number(vj.scale)
        else:
            si = scene.track.sigma(bi, np.asarray(q_i[mask], dtype=float))
            sj = scene.track.sigma(bj, np.asarray(q_j[mask], dtype=float))
            vi1, vj1 = law.variables(bi, 1), law.variables(bj, 1)
            ci, cj = float(vi1.scale) * si**law.scale_power, float(vj1.scale) * sj**law.scale_power
            mi, mj = float(vi1.inertia) * si**law.inertia_power, float(vj1.inertia) * sj**law.inertia_power
        du = ci * dphi_i[mask] - cj * dphi_j[mask]
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
    #: Junction passages and limiter impacts (see events.CollisionLog.passages and passage_table);
    #: a run streamed to a sink that takes them keeps only the first chunk here (the file has them all).
    passages: tuple = ()
    #: (junction passages, limiter impacts) in the whole run (streamed ones included).
    passage_counts: tuple | None = None
    #: With RunOptions(dense=True): (t0, t1, heyoka continuous output, expand, whole turns) per propagation.
    dense: tuple | None = None
    #: Rough tracks: every change of a body's friction mode, (t, body (0-based), from, to, q, q')
    #: (see transition_table); each body's mode and slip velocity w (m/s) at the end.
    transitions: tuple = ()
    #: Rough tracks: per kept collision the modes of bodies i and j before and after it (MODE_COLUMNS),
    #: and the speed each body's spin rolls at where it slips (nan: rolling; the table's energies).
    collision_modes: np.ndarray | None = None
    collision_spins: np.ndarray | None = None
    final_modes: tuple = ()
    final_slip: tuple = ()
    #: The work friction dissipated on each body (J; a cluster's on its first member), integrated
    #: with the motion; per transition, the body's unit's total since t = 0 at that instant.
    friction_work: tuple = ()
    transition_work: tuple = ()
    #: Forced runs: the stroboscopic section, (t, full state) once a forcing period.
    strobe: tuple = ()

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

    def body_energies(self, states) -> np.ndarray:
        """Each body's energy (columns) in each state row, float64."""
        return np.asarray(state_energies(self.scene, states), dtype=float)

    def energy(self, state) -> float:
        return float(self.body_energies(state).sum())

    @property
    def junctions(self) -> list[dict]:
        """Junction passages: t, body, from and to piece (from 1), q."""
        return [{"t": float(t), "body": b + 1, "from": f + 1, "to": to + 1, "q": float(q)}
                for t, b, kind, f, to, q, _v, _w in self.passages if kind == 0]

    @property
    def limiter_impacts(self) -> list[dict]:
        """Limiter impacts: t, body, end (lower | upper), q, v_before, v_after."""
        return [{"t": float(t), "body": b + 1, "end": "lower" if kind == 1 else "upper", "q": float(q),
                 "v_before": float(v), "v_after": float(w)}
                for t, b, kind, _f, _to, q, v, w in self.passages if kind != 0]

    @property
    def warnings(self) -> list[str]:
        return list(self.settings.get("warnings", []))

    def passage_table(self, native: bool = False) -> np.ndarray:
        """Junction passages and limiter impacts, columns PASSAGE_COLUMNS (bodies and pieces from 1); float64, or
        with ``native=True`` a long, quad or MPFR run's own numbers (object columns, for full digits in text)."""
        return passage_table(self.passages, native=native and self.precision.name != "double")

    def sample(self, n_points: int = 2000):
        """(t, states) on a uniform grid over the run, from the dense output (run with dense=True)."""
        t = np.linspace(0.0, float(self.t_final), n_points)
        return t, self.states_at(t)

    def states_at(self, t) -> np.ndarray:
        """Full states (float64, rows) at the ascending times ``t``, from the dense output (dense=True)."""
        if not self.dense:
            raise ValueError("run with RunOptions(dense=True) to sample the trajectory")
        t = np.asarray(t, dtype=float)
        out = np.empty((t.size, 2 * self.n_bodies))
        starts = np.array([d[0] for d in self.dense])
        idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(self.dense) - 1)
        for k, (t0, t1, c_out, expand, turns) in enumerate(self.dense):
            sel = idx == k
            if np.any(sel):
                values = np.asarray(c_out(np.clip(t[sel], t0, t1)), dtype=float)
                # A mode with clusters on the circle integrates one angle per unit: back to every body.
                # (Rough tracks: slip velocities and friction work follow the rates: dropped here.)
                out[sel] = values[:, : 2 * self.n_bodies] if expand is None else \
                    np.array([expand(row) for row in values.tolist()])
                if turns:  # the whole turns taken out of the angles then (simulation.turns)
                    out[sel, : self.n_bodies] += float(turns)
        return out

    @property
    def energy_initial(self) -> float:
        return self.energy(self.initial_state) + self.slip_energy(self.initial_state, self.scene.slip)

    @property
    def energy_final(self) -> float:
        return self.energy(self.final_state) + self.slip_energy(self.final_state, self.final_slip)

    def slip_energy(self, state, slip) -> float:
        """The kinetic energy a slipping body's spin adds to (or takes from) its rolling energy:
        1/2 m (kappa - 1) [(v - w)^2 - v^2], v = sigma q' (rough tracks; 0 when every body rolls)."""
        total = 0.0
        n = self.n_bodies
        for k, w in enumerate(slip):
            w = float(w)
            if w == 0:
                continue
            body = self.scene.bodies[k]
            v = float(self.scene.track.sigma(body, float(state[k]))) * float(state[n + k])
            total += 0.5 * float(body.mass) * (float(body.kappa) - 1) * ((v - w) ** 2 - v * v)
        return total

    def transition_table(self, native: bool = False) -> np.ndarray:
        """Changes of friction mode, columns TRANSITION_COLUMNS (bodies from 1); float64, or with
        ``native=True`` a quad or MPFR run's own numbers (object columns, for full digits in text)."""
        return transition_table(self.transitions, native=native and self.precision.name != "double")

    @property
    def strobe_table(self) -> np.ndarray:
        """The stroboscopic section: rows t, q_1..q_N, dq_1..dq_N (float64)."""
        return self.strobe_rows()

    def strobe_rows(self, native: bool = False) -> np.ndarray:
        """The stroboscopic section's rows t, q_1..q_N, dq_1..dq_N: float64, or with ``native=True``
        a quad or MPFR run's own numbers (an object array)."""
        n = self.n_bodies
        native = native and self.precision.name != "double"
        out = np.zeros((len(self.strobe), 1 + 2 * n), dtype=object if native else float)
        for r, (t, state) in enumerate(self.strobe):
            out[r, 0] = t if native else float(t)
            out[r, 1:] = list(state[: 2 * n]) if native else np.asarray([float(x) for x in state[: 2 * n]])
        return out

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
            self.states_before, self.states_after, self.law_flags, native=native, modes=self.collision_modes,
            spins=self.collision_spins,
        )

    def summary(self) -> dict:
        """The run in a JSON-ready dictionary (see README, "Outputs")."""
        nb = self.n_bodies
        final = np.asarray(self.final_state, dtype=float)
        c = self.scene.coordinate
        kinds = [row[2] for row in self.passages]
        junctions, impacts = self.passage_counts or (sum(1 for x in kinds if x == 0), sum(1 for x in kinds if x != 0))
        return {
            "status": self.status.value,
            "message": self.message,
            "collisions": self.n_collisions,
            "limiter_impacts": impacts,
            "junction_passages": junctions,
            "t_final": float(self.t_final),
            "energy_initial": self.energy_initial,
            "energy_final": self.energy_final,
            "track": self.scene.track.kind,
            "coordinate": c,
            "frame": {"omega": float(self.scene.frame.omega), "axis_x": float(self.scene.frame.axis_x)},
            "final_state": [
                {"body": k + 1, "q": float(final[k]), "dq": float(final[nb + k])} for k in range(nb)
            ],
            "wall_time_s": self.wall_time_s,
            "steps": self.steps,
            "precision": self.precision.name,
            "significant_digits": self.precision.digits,
            "t_final_text": self.precision.format(self.t_final),
            # the run's own digits (long, quad, mp): a run continued from its summary starts where it ended
            "final_state_text": [{"body": k + 1, "q": self.precision.format(self.final_state[k]),
                                  "dq": self.precision.format(self.final_state[nb + k])} for k in range(nb)],
            "law": self.scene.law.name,
            "restitution": float(self.scene.law.restitution),
            "contact_intervals": list(self.contact_intervals),
            **self._friction_summary(),
            **self.settings,
        }

    def _friction_summary(self) -> dict:
        scene = self.scene
        out = {}
        if scene.rough:
            out["friction"] = {
                "mu": float(scene.track_friction), "mu_s": float(scene.static_coefficient),
                "transitions": len(self.transitions),
                "work": float(sum(self.friction_work)),
                "final_modes": [{"body": k + 1, "mode": m, "slip": float(w)}
                                for k, (m, w) in enumerate(zip(self.final_modes, self.final_slip))],
            }
        if scene.forcing is not None:
            f = scene.forcing
            out["forcing"] = {"kind": f.kind, "amplitude": float(f.amplitude), "frequency": float(f.frequency),
                              "phase": float(f.phase), "period": f.period, "strobe_samples": len(self.strobe)}
        return out


def passage_table(passages, first_number: int = 1, native: bool = False) -> np.ndarray:
    """Passage records -> structured array (columns PASSAGE_COLUMNS; kind 0 junction, 1/2 lower/upper limiter),
    numbered from ``first_number``; ``native``: t, q and the rates as recorded (a long, quad or MPFR run's own
    numbers, object columns, for full digits in text: passages.csv had 17 digits of a quad run, review)."""
    number = object if native else np.float64
    dtype = [(c, np.int64 if c in ("n", "body", "kind", "piece_from", "piece_to") else number)
             for c in PASSAGE_COLUMNS]
    table = np.zeros(len(passages), dtype=dtype)
    value = (lambda x: x) if native else float
    for n, (t, body, kind, p_from, p_to, q, v, v_new) in enumerate(passages):
        table[n] = (first_number + n, value(t), body + 1, kind, p_from + 1, p_to + 1, value(q), value(v), value(v_new))
    return table


def transition_table(transitions, first_number: int = 1, native: bool = False) -> np.ndarray:
    """Friction transitions -> structured array, columns TRANSITION_COLUMNS (mode names as text);
    ``native``: t, q, dq as recorded (a quad or MPFR run's own numbers, object columns)."""
    number = object if native else np.float64
    dtype = [("n", np.int64), ("t", number), ("body", np.int64), ("from", "U8"), ("to", "U8"),
             ("q", number), ("dq", number)]
    table = np.zeros(len(transitions), dtype=dtype)
    convert = (lambda x: x) if native else float
    for n, (t, body, old, new, q, dq) in enumerate(transitions):
        table[n] = (first_number + n, convert(t), body + 1, old, new, convert(q), convert(dq))
    return table
