"""Files of the analyses of one body on a track: equilibria and the phase portrait.

The same files on every track: on an open track in (x, x') or (s, s'), on a
circle in (phi, phi') with phi in [-pi, pi).

``write_portrait``: portrait.png, energy_surface.png, bifurcation.png and
portrait.json (equilibria, bifurcations, the check of the portrait against
integrated trajectories). Every file is written atomically.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..analysis.equilibria import bifurcations, find_equilibria, problem_of
from ..model.scene import Scene
from .outputs import atomic_write_text, versions


def equilibria_list(scene: Scene, body: int = 0) -> list:
    return find_equilibria(problem_of(scene, body))


def default_omegas(scene: Scene) -> np.ndarray:
    """0 to twice the largest of the scene's Omega and a scale of the track's bifurcations.

    That scale is 3 rad/s on an open track and, on a circle, sqrt(g / rho) for
    the smallest centre-path radius rho = R - r, the pitchfork of the bottom.
    """
    om = float(scene.frame.omega)
    if scene.track.closed:
        rho = min(float(scene.track.path_radius(b)) for b in scene.bodies)
        return np.linspace(0.0, 2 * max(om, float(np.sqrt(float(scene.g) / rho))), 121)
    return np.linspace(0.0, 2 * max(om, 3.0), 121)


def write_portrait(scene: Scene, out_dir: Path, *, scene_source: str, body: int = 0, omegas=None,
                   progress=None) -> dict:
    """``progress``: called as ``progress(done, total, stage)`` before each figure and at the end."""
    from .portrait_figures import bifurcation_figure, energy_surface_figure, portrait_figure

    def stage(done, name):
        if progress is not None:
            progress(done, 4, name)

    out_dir.mkdir(parents=True, exist_ok=True)
    omegas = default_omegas(scene) if omegas is None else omegas
    stage(0, "phase portrait")
    check = portrait_figure(scene, out_dir / "portrait.png", body=body)
    stage(1, "energy surface")
    energy_surface_figure(scene, out_dir / "energy_surface.png", body=body)
    stage(2, "bifurcation diagram")
    bifurcation_figure(scene, out_dir / "bifurcation.png", omegas, body=body)
    stage(3, "equilibria")
    problem = problem_of(scene, body)
    eq = find_equilibria(problem)
    bif = bifurcations(problem, omegas)
    data = {
        "scene": scene.name, "scene_source": scene_source, "body": body + 1,
        "track": scene.track.kind, "coordinate": scene.coordinate,
        "omega": float(scene.frame.omega), "axis_x": float(scene.frame.axis_x),
        "equilibria": [{"x": e.x, "q": e.q, "type": e.type, "stiffness": e.stiffness,
                        "potential_per_mass": e.potential,
                        **({"x_end": e.x_end, "q_end": e.q_end} if e.x_end is not None else {})} for e in eq],
        "separatrix_levels_per_mass": sorted({e.potential for e in eq if e.type == "saddle"}),
        "bifurcations": [{"omega": b.omega, "x": b.x, "q": b.q, "equilibria_before": b.before,
                          "equilibria_after": b.after} for b in bif],
        "omega_range": [float(omegas[0]), float(omegas[-1])],
        "check": {"integrated_trajectories": check.trajectories, "duration_s": check.duration,
                  "worst_relative_first_integral_drift": check.worst_relative_drift},
        "files": {"portrait": "portrait.png", "energy_surface": "energy_surface.png",
                  "bifurcation": "bifurcation.png"},
        "versions": versions(),
    }
    atomic_write_text(out_dir / "portrait.json", json.dumps(data, indent=2) + "\n")
    stage(4, "done")
    return data
