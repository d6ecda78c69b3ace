"""Dense samples of a finished run, for phase portraits and energy plots.

Between two collisions (or mode changes) the units move independently on
their own phase curves; each piece is re-integrated from its starting state
with the scene's event-free system of the mode then in force (the same
compiled code, no events), so a plot never needs the run to keep dense output.
Samples are in double whatever the run's precision (for plots and gap checks
at 1e-12 rad; heyoka's quad and MPFR integrators also take no float state).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import heyoka as hy
import numpy as np

from .precision import DOUBLE
from .result import SimulationResult
from .system import Unit, build_system, cluster_unit, singleton_units


@dataclass(frozen=True)
class Branch:
    """Samples of one interval between collisions: times (k,), full states (k, 2N)."""

    times: np.ndarray
    states: np.ndarray


def _units(scene, mode) -> tuple[Unit, ...]:
    """Units of a mode given its (clusters, pinned units) (1-based body numbers)."""
    clusters, pinned = mode
    held = dict(pinned)
    in_cluster = {k - 1 for c in clusters for k in c}
    units = [cluster_unit(scene, tuple(k - 1 for k in c), pinned=held.get(c, "")) for c in clusters]
    units += [dataclasses.replace(u, pinned=held.get((u.members[0] + 1,), ""))
              for u in singleton_units(len(scene.bodies)) if u.members[0] not in in_cluster]
    return tuple(sorted(units, key=lambda u: u.members[0]))


def sample_branches(result: SimulationResult, *, max_branches: int | None = None, points: int = 200) -> list[Branch]:
    """The run split at its collisions and mode changes, each piece sampled at ``points`` times.

    Branch 0 starts at t = 0; every collision and every change of contact
    mode starts a new branch; the last one ends at the end of the run (or of
    the collisions kept in memory, for a streamed run).
    """
    scene = result.scene
    modes = [(float(m.t), np.asarray(m.state, dtype=float), (m.clusters, m.pinned)) for m in result.mode_changes]
    if not modes:
        modes = [(0.0, np.asarray(result.initial_state, dtype=float), ((), ()))]
    clusters_at = sorted(modes, key=lambda b: b[0])
    # At equal times a mode change comes after the collision that caused it
    # (the branch then starts from the merged state); the initial mode first.
    tagged = [(float(t), 0, np.asarray(s, dtype=float), None) for t, s in zip(result.times, result.states_after)]
    tagged += [(t, -1 if n == 0 else 1, state, clusters) for n, (t, state, clusters) in enumerate(modes)]
    tagged.sort(key=lambda b: (b[0], b[1]))
    breaks = [(t, state, clusters) for t, _, state, clusters in tagged]
    streamed = result.kept_collisions < result.n_collisions
    t_stop = float(result.times[-1]) if streamed and result.kept_collisions else float(result.t_final)
    breaks = [b for b in breaks if b[0] <= t_stop]
    ends = [b[0] for b in breaks[1:]] + [t_stop]
    if max_branches is not None:
        # Each branch ends at the next collision or mode change even when later ones are not
        # drawn (measured before: the last branch ran without collisions to t_end, through the
        # other ball).
        breaks = breaks[:max_branches]
    if scene.rough or scene.forcing is not None:
        return _dense_branches(result, breaks, ends, points, t_stop)
    integrators: dict = {}
    branches = []
    for n, (t0, state, _) in enumerate(breaks):
        t1 = ends[n]
        clusters = [c for (tc, _, c) in clusters_at if tc <= t0][-1]
        if clusters not in integrators:
            system = build_system(scene, DOUBLE, units=_units(scene, clusters), events=False)
            ta = hy.taylor_adaptive(system.equations, system.reduce(list(state)), pars=system.parameters)
            integrators[clusters] = (system, ta)
        system, ta = integrators[clusters]
        ta.time = t0
        ta.state[:] = system.reduce(list(state))
        # A branch a few ulps long (two events 2e-16 s apart) gives a linspace
        # with repeated values, which propagate_grid rejects: keep each time once.
        grid = np.unique(np.linspace(t0, t1, points)) if t1 > t0 else np.array([t0])
        out = np.array(ta.propagate_grid(grid)[-1], dtype=float)
        full = np.array([system.expand(row) for row in out.tolist()])
        branches.append(Branch(times=grid, states=full))
    return branches


def _dense_branches(result, breaks, ends, points, t_stop) -> list[Branch]:
    """Rough tracks and forced runs: the motion between collisions also depends on each body's
    friction mode and on time, so the branches are read from the run's dense output (the run is
    repeated in double with dense output where it was not kept)."""
    if not result.dense:
        from .driver import simulate

        result = simulate(result.scene, t_end=t_stop, max_collisions=None, dense=True)
    if not result.dense:  # a run that stopped before its first step: the recorded states alone
        return [Branch(times=np.array([t0]), states=np.atleast_2d(np.asarray(state, dtype=float)))
                for t0, state, _ in breaks]
    branches = []
    for n, (t0, _state, _) in enumerate(breaks):
        t1 = ends[n]
        grid = np.unique(np.linspace(t0, t1, points)) if t1 > t0 else np.array([t0])
        branches.append(Branch(times=grid, states=result.states_at(grid)))
    return branches
