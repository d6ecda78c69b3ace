"""Dense samples of a finished run, for phase portraits and energy plots.

Between two collisions the bodies move independently on their own phase
curves; each branch is re-integrated from its post-collision state with the
scene's event-free system (the same compiled code, no events), so a plot
never needs the run to keep dense output.
"""

from __future__ import annotations

from dataclasses import dataclass

import heyoka as hy
import numpy as np

from .result import SimulationResult
from .system import build_system


@dataclass(frozen=True)
class Branch:
    """Samples of one interval between collisions: times (k,), states (k, 2N)."""

    times: np.ndarray
    states: np.ndarray


def sample_branches(result: SimulationResult, *, max_branches: int | None = None, points: int = 200) -> list[Branch]:
    """The run split at its collisions, each piece sampled at ``points`` times.

    Branch 0 runs from t = 0 to the first collision; branch n from collision
    n to collision n + 1 (or to the end of the run).
    """
    system = build_system(result.scene, result.precision, pairs=())
    ta = hy.taylor_adaptive(
        system.equations, system.initial_state, pars=system.parameters, **result.precision.integrator_options()
    )
    starts = [0.0] + [float(t) for t in result.times]
    ends = [float(t) for t in result.times] + [float(result.t_final)]
    states = [np.asarray(result.initial_state, dtype=float)] + [np.asarray(s, dtype=float) for s in result.states_after]
    if max_branches is not None:
        starts, ends, states = starts[:max_branches], ends[:max_branches], states[:max_branches]
    branches = []
    for t0, t1, s0 in zip(starts, ends, states):
        ta.time = t0
        ta.state[:] = s0
        grid = np.linspace(t0, t1, points) if t1 > t0 else np.array([t0])
        out = ta.propagate_grid(grid)
        branches.append(Branch(times=grid, states=np.array(out[-1], dtype=float)))
    return branches
