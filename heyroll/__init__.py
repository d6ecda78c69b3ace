"""heyroll: collisions of bodies in rolling and the vibro-impact dynamics they drive.

Public API (everything else is private and may change):

    scene = heyroll.load_scene("scene.toml")      # or heyroll.default_scene()
    result = heyroll.simulate(scene)
    table = result.collision_table()              # numpy structured array

A billiard table (paper section 7) is a ``TableScene`` (``[track] type = "table"``
in a scene file, or ``TableScene.make(EllipseBoundary(a, b), [TableBall.make(...)])``);
``simulate`` runs it on the same engine and returns a ``TableResult``.

Layers, with one-way imports: ``heyroll.model`` (bodies, tracks, laws) ->
``heyroll.simulation`` (heyoka systems, events, driver, results) ->
``heyroll.interfaces`` (scene files, CLI, figures, reports).
``heyroll.reference`` is an independent mpmath solution used for validation.
"""

from ._version import __version__
from .errors import SceneError, SceneFileError

# Every other name is imported on first use: the model's tracks build heyoka expressions, the interfaces load
# matplotlib, and ``import heyroll`` (which the ``heyroll`` command does before anything else) stays instant,
# so a Ctrl-C while the command starts is caught by it (heyroll.__main__) rather than printed as a traceback.
_MODEL = {
    "heyroll.model.bodies": ("Body", "Shape"),
    "heyroll.model.laws": ("CollisionLaw", "GeneralizedNewtonLaw", "HedrihRollingLaw", "NewtonCentreLaw", "make_law"),
    "heyroll.model.frame": ("Frame",),
    "heyroll.model.scene": ("RunSettings", "Scene"),
    "heyroll.model.tracks": ("ArcChainTrack", "CircleTrack", "CurveTrack", "Segment", "ThreeArcTrack", "Track"),
    "heyroll.model.table": ("CircleBoundary", "EllipseBoundary", "PolygonBoundary", "RectangleBoundary",
                            "TableBall", "TableScene"),
}
_LAZY = {name: (module, name) for module, names in _MODEL.items() for name in names}
_LAZY |= {
    "simulate": ("heyroll.simulation.driver", "simulate"),
    "simulate_batch": ("heyroll.simulation.batch", "simulate_batch"),
    "Precision": ("heyroll.simulation.precision", "Precision"),
    "SimulationResult": ("heyroll.simulation.result", "SimulationResult"),
    "TableResult": ("heyroll.simulation.table.result", "TableResult"),
    "IMPACT_COLUMNS": ("heyroll.simulation.table.result", "IMPACT_COLUMNS"),
    "periodic_orbits": ("heyroll.analysis.billiard_orbits", "periodic_orbits"),
    "Status": ("heyroll.simulation.result", "Status"),
    "TABLE_COLUMNS": ("heyroll.simulation.result", "TABLE_COLUMNS"),
    "RunOptions": ("heyroll.simulation.driver", "RunOptions"),
    "EquilibriumProblem": ("heyroll.analysis.equilibria", "EquilibriumProblem"),
    "find_equilibria": ("heyroll.analysis.equilibria", "find_equilibria"),
    "bifurcations": ("heyroll.analysis.equilibria", "bifurcations"),
    "default_scene": ("heyroll.interfaces.scene_file", "default_scene"),
    "load_scene": ("heyroll.interfaces.scene_file", "load_scene"),
    "parse_scene": ("heyroll.interfaces.scene_file", "parse_scene"),
}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        module, attribute = _LAZY[name]
        value = getattr(importlib.import_module(module), attribute)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'heyroll' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))


__all__ = [
    "ArcChainTrack",
    "CircleBoundary",
    "EllipseBoundary",
    "IMPACT_COLUMNS",
    "PolygonBoundary",
    "RectangleBoundary",
    "TableBall",
    "TableResult",
    "TableScene",
    "periodic_orbits",
    "Body",
    "CurveTrack",
    "EquilibriumProblem",
    "Frame",
    "RunOptions",
    "Segment",
    "ThreeArcTrack",
    "Track",
    "bifurcations",
    "find_equilibria",
    "CircleTrack",
    "CollisionLaw",
    "GeneralizedNewtonLaw",
    "HedrihRollingLaw",
    "NewtonCentreLaw",
    "Precision",
    "RunSettings",
    "Scene",
    "SceneError",
    "SceneFileError",
    "Shape",
    "SimulationResult",
    "Status",
    "TABLE_COLUMNS",
    "__version__",
    "default_scene",
    "load_scene",
    "make_law",
    "parse_scene",
    "simulate",
    "simulate_batch",
]
