"""The heyoka ODE system of a scene: only the bodies, terms and events it needs.

State layout: [phi_1 .. phi_N, dphi_1 .. dphi_N]. Between collisions each
body is a rolling pendulum, phi'' = -g/(kappa (R - r)) sin phi (paper eq. 25).
All scene constants enter as runtime parameters, so scenes of the same shape
(same N, same set of reachable contacts) share one compiled integrator.
"""

from __future__ import annotations

from dataclasses import dataclass

import heyoka as hy

from ..model.scene import ContactPair, Scene
from .precision import Precision


@dataclass(frozen=True)
class SceneSystem:
    """Expressions and parameter values of a scene at one precision."""

    equations: list
    parameters: list
    initial_state: list
    pairs: tuple[ContactPair, ...]
    gap_expressions: list
    gap_parameter_index: dict[int, int]
    n_bodies: int
    precision: Precision
    law_name: str = ""


def build_system(scene: Scene, precision: Precision, *, pairs: tuple[ContactPair, ...] | None = None) -> SceneSystem:
    """The ODEs for every body and a gap function for each contact ``pairs`` lists.

    By default the pairs are those the scene's energy can reach; pass
    ``pairs=scene.pairs`` to watch all of them.
    """
    n = len(scene.bodies)
    phi = hy.make_vars(*[f"phi_{k + 1}" for k in range(n)]) if n > 1 else [hy.make_vars("phi_1")]
    dphi = hy.make_vars(*[f"dphi_{k + 1}" for k in range(n)]) if n > 1 else [hy.make_vars("dphi_1")]
    num = precision.number
    params = [num(scene.track.angular_stiffness(b, scene.g)) for b in scene.bodies]
    equations = [(phi[k], dphi[k]) for k in range(n)]
    equations += [(dphi[k], -hy.par[k] * hy.sin(phi[k])) for k in range(n)]
    if pairs is None:
        pairs = tuple(p for p in scene.pairs if p.reachable)
    gaps = []
    gap_index = {}
    for p in pairs:
        idx = len(params)
        params.append(num(p.gap_constant()))
        gap_index[id(p)] = idx
        gaps.append(phi[p.j] - phi[p.i] + hy.par[idx])
    state = [num(x) for x in scene.phi] + [num(x) for x in scene.dphi]
    return SceneSystem(
        equations=equations,
        parameters=params,
        initial_state=state,
        pairs=tuple(pairs),
        gap_expressions=gaps,
        gap_parameter_index=gap_index,
        n_bodies=n,
        precision=precision,
        law_name=scene.law.name,
    )


def gap_value(system: SceneSystem, pair_number: int, state) -> float:
    """Gap of the pair-th watched contact, phi_j + offset - phi_i - beta, in rad."""
    p = system.pairs[pair_number]
    return state[p.j] - state[p.i] + system.parameters[system.gap_parameter_index[id(p)]]
